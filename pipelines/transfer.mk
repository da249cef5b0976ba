# Motion transfer (transfer paper, sections 4 to 7; gpr-nn also runs gpr-predict --surface correct and
# correct-stitch, i.e. section 6, recorded as methods gpr-nn+correct and gpr-nn+correct+stitch):
#   make transfer SET=<capture set> OUT=<dir>     (defaults: SET=$(OUT)/demo/set, OUT=out)
# Writes $(OUT)/transfer/<src>-to-<tgt>/<motion>/<method>/NNNNNN.ply, contact sheets under
# $(OUT)/render/, learning curves under $(OUT)/learning-curves/ and $(OUT)/results.json.
# Intermediate artifacts go to $(OUT)/work/. The per-motion rules are generated from set.json into
# $(OUT)/work/transfer-rules.mk (python3). Idempotent (make's timestamps) and `make -j` safe.

SET ?= $(OUT)/demo/set
TRANSFER_METHODS ?= gpr-nn gpr-se gpr-linear keypose-affine whole-body
# align --frame: root (poses fitted on the torso core, the default) or body (the paper's whole mesh)
ALIGN_FRAME ?= root
# pca-fit --part-alignment: body (parts cut from the aligned frames) or part (each part Procrustes-aligned)
PART_ALIGNMENT ?= body
# gpr-predict --placement of every method's output (gpr-nn is also placed the other two ways)
PLACEMENT ?= scaled-source
# gpr-train --mean: affine (least-squares affine map, GP on the residuals) or zero (the paper)
GPR_MEAN ?= affine
# Further gpr-train flags for every model (e.g. --learn-noise, --nn-bias), and pca-fit components
GPR_TRAIN_FLAGS ?=
PCA_COMPONENTS ?= 20
TRANSFER_WORK := $(OUT)/work
TRANSFER_RULES := $(TRANSFER_WORK)/transfer-rules.mk
TRANSFER_BINS := align segment pca-fit dtw-densify gpr-train gpr-predict evaluate learning-curves paper-figure render

.PHONY: transfer transfer-results transfer-report
transfer:
	@test -f $(SET)/set.json || { echo "transfer: $(SET)/set.json: no capture set (run 'make demo' or pass SET=<dir>)" >&2; exit 1; }
	$(CARGO) build --release --workspace --quiet
	@$(MAKE) --no-print-directory transfer-results SET=$(SET) OUT=$(OUT)
	@$(MAKE) --no-print-directory transfer-report SET=$(SET) OUT=$(OUT)

# The generated rules: one block per subject, motion, pair, direction and method.
define TRANSFER_RULES_PY
import json, os, sys
set_dir, out, methods = sys.argv[1], sys.argv[2], sys.argv[3].split()
W = out + "/work"
spec = json.load(open(os.path.join(set_dir, "set.json")))
S, T = spec["source"], spec["target"]
subj = {x: json.load(open(os.path.join(set_dir, x, "subject.json"))) for x in (S, T)}
fps = {x: float(subj[x]["fps"]) for x in (S, T)}
def motions(x):
    d = os.path.join(set_dir, x)
    return sorted(m for m in os.listdir(d) if os.path.isdir(os.path.join(d, m)))
def frames(d):
    return sorted(f for f in os.listdir(d) if f.split(".")[-1].lower() in ("ply", "obj") and f.split(".")[0].isdigit())
train = {S: [p["source"] for p in spec["train"]], T: [p["target"] for p in spec["train"]]}
def template(x):
    t = subj[x].get("template")
    if t:
        return os.path.join(set_dir, x, t)
    d = os.path.join(set_dir, x, train[x][0])
    return os.path.join(d, frames(d)[0])
tpl = {x: template(x) for x in (S, T)}
# The whole-body comparison at the parts' total dimension (CVPR fig. 9: "equivalent total number of
# input and output dimensions").
whole_components = {x: int(sys.argv[5]) * len(subj[x]["parts"]) for x in (S, T)}
# evaluate's foot-sliding inputs: the subject's truth contacts, its parts and its template.
feet = {x: "--contacts %s --segmentation %s/%s/parts.seg --template %s" % (os.path.join(set_dir, x, "subject.json"), W, x, tpl[x]) for x in (S, T)}
B = "$$(BIN)"
rules, results, stamps = [], [], []
def rule(target, deps, *cmds):
    rules.append("%s: %s\n%s\n" % (target, " ".join(deps), "".join("\t%s\n" % c for c in cmds)))
for x in (S, T):
    for m in motions(x):
        d = os.path.join(set_dir, x, m)
        rule("%s/%s/%s.aligned" % (W, x, m), [B + "/align", tpl[x], "%s/%s/parts.seg" % (W, x)] + [os.path.join(d, f) for f in frames(d)],
             "@mkdir -p $$(@D)", "%s/align -q --frame $$(ALIGN_FRAME) --segmentation %s/%s/parts.seg --template %s %s --out $$@" % (B, W, x, tpl[x], d))
    rule("%s/%s/parts.seg" % (W, x), [B + "/segment", os.path.join(set_dir, x, "subject.json"), tpl[x]],
         "@mkdir -p $$(@D)", "%s/segment -q %s --template %s --out $$@" % (B, os.path.join(set_dir, x, "subject.json"), tpl[x]))
    aligned = ["%s/%s/%s.aligned" % (W, x, m) for m in train[x]]
    rule("%s/%s/pca.model" % (W, x), [B + "/pca-fit", "%s/%s/parts.seg" % (W, x)] + aligned,
         "%s/pca-fit -q --components $$(PCA_COMPONENTS) --part-alignment $$(PART_ALIGNMENT) --template %s --parts %s/%s/parts.seg %s --out $$@ --report %s/%s/pca.json" % (B, tpl[x], W, x, " ".join(aligned), W, x))
    rule("%s/%s/pca-whole.model" % (W, x), [B + "/pca-fit"] + aligned,
         "%s/pca-fit -q --whole-body --components %d --template %s %s --out $$@ --report %s/%s/pca-whole.json" % (B, whole_components[x], tpl[x], " ".join(aligned), W, x))
pair_args = []
corrs = []
for p in spec["train"]:
    c = "%s/pairs/%s.corr" % (W, p["source"])
    sa, ta = "%s/%s/%s.aligned" % (W, S, p["source"]), "%s/%s/%s.aligned" % (W, T, p["target"])
    rule(c, [B + "/dtw-densify", os.path.join(set_dir, "set.json"), sa, ta, "%s/%s/pca.model" % (W, S), "%s/%s/pca.model" % (W, T)],
         "@mkdir -p $$(@D)",
         "%s/dtw-densify -q --set %s --pair %s --source-pca %s/%s/pca.model --target-pca %s/%s/pca.model --target-fps %g %s %s --out $$@ --report %s/pairs/%s.json"
         % (B, os.path.join(set_dir, "set.json"), p["source"], W, S, W, T, fps[T], sa, ta, W, p["source"]))
    pair_args.append("--pair %s %s %s" % (sa, ta, c))
    corrs += [sa, ta, c]
# Directions: forward tests the set's test motions; reverse tests the target's motions that have truth
# for the source subject (plus an optional "target_test" list in set.json).
rev_tests = sorted(set(m for m in motions(T) if os.path.isdir(os.path.join(set_dir, "truth", S, m))) | set(spec.get("target_test", [])))
directions = [(S, T, False, spec.get("test", [])), (T, S, True, rev_tests)]
variants = [(m, m, False) for m in methods] + [("gpr-nn-keyposes", "gpr-nn", True)]
for (src, tgt, rev, tests) in directions:
    dn = "%s-to-%s" % (src, tgt)
    label = "%s->%s" % (src, tgt)
    for (name, method, keys) in variants:
        pca = "pca-whole" if method == "whole-body" else "pca"
        model = "%s/models/%s/%s.model" % (W, dn, name)
        rule(model, [B + "/gpr-train", "%s/%s/%s.model" % (W, src, pca), "%s/%s/%s.model" % (W, tgt, pca)] + corrs,
             "@mkdir -p $$(@D)",
             "%s/gpr-train -q --mean $$(GPR_MEAN) $$(GPR_TRAIN_FLAGS) --method %s %s %s --source-pca %s/%s/%s.model --target-pca %s/%s/%s.model --source-fps %g --target-fps %g %s --out $$@"
             % (B, method, "--keyposes-only" if keys else "", "--reverse" if rev else "", W, src, pca, W, tgt, pca, fps[src], fps[tgt], " ".join(pair_args)))
        stamps.append(model)
        for m in tests:
            if not os.path.isdir(os.path.join(set_dir, src, m)):
                continue
            truth = os.path.join(set_dir, "truth", tgt, m)
            default_pl = sys.argv[4]
            places = [default_pl] + ([p for p in ("scaled-source", "regressed", "blended") if p != default_pl] if name == "gpr-nn" else [])
            for pl in places:
                seq = "%s/transfer/%s/%s/%s" % (out, dn, m, name) if pl == default_pl else "%s/placement/%s/%s/%s" % (W, dn, m, pl)
                timing = "%s/predict/%s/%s/%s-%s.json" % (W, dn, m, name, pl)
                rule(timing, [B + "/gpr-predict", model, "%s/%s/%s.aligned" % (W, src, m)],
                     "@mkdir -p $$(@D)",
                     "%s/gpr-predict -q --model %s --source-pca %s/%s/%s.model --target-pca %s/%s/%s.model --target-template %s --placement %s %s/%s/%s.aligned --out %s --timing $$@"
                     % (B, model, W, src, pca, W, tgt, pca, tpl[tgt], pl, W, src, m, seq))
                stamps.append(timing)
                if os.path.isdir(truth):
                    rec = "%s/eval/%s/%s/%s-%s.json" % (W, dn, m, name, pl)
                    rule(rec, [B + "/evaluate", timing],
                         "@mkdir -p $$(@D)",
                         "%s/evaluate -q %s %s %s --direction '%s' --motion %s --method %s --placement %s --training %s --out $$@"
                         % (B, seq, truth, feet[tgt], label, m, method, pl, "keyposes" if keys else "dense"))
                    results.append(rec)
            if name == "gpr-nn":
                # Paper section 6 after the regression: correction (M = 3), then stitching.
                for (surf, meth) in (("correct", "gpr-nn+correct"), ("correct-stitch", "gpr-nn+correct+stitch")):
                    seq = "%s/transfer/%s/%s/%s" % (out, dn, m, meth)
                    timing = "%s/predict/%s/%s/%s-%s.json" % (W, dn, m, meth, default_pl)
                    training = ["%s/%s/%s.aligned" % (W, tgt, t) for t in train[tgt]]
                    # Per-frame confidence (docs/FORMATS.md) beside the full pipeline's output.
                    conf_dir = "%s/confidence/%s" % (W, dn)
                    conf_arg = " --confidence %s/%s.json" % (conf_dir, m) if surf == "correct-stitch" else ""
                    rule(timing, [B + "/gpr-predict", model, "%s/%s/%s.aligned" % (W, src, m), "%s/%s/parts.seg" % (W, tgt)] + training,
                         "@mkdir -p $$(@D) %s" % conf_dir,
                         "%s/gpr-predict -q --model %s --source-pca %s/%s/pca.model --target-pca %s/%s/pca.model --target-template %s --placement %s --surface %s --segmentation %s/%s/parts.seg %s -m 3 %s/%s/%s.aligned --out %s --timing $$@%s"
                         % (B, model, W, src, W, tgt, tpl[tgt], default_pl, surf, W, tgt, " ".join("--target-training " + t for t in training), W, src, m, seq, conf_arg))
                    stamps.append(timing)
                    if os.path.isdir(truth):
                        rec = "%s/eval/%s/%s/%s-%s.json" % (W, dn, m, meth, default_pl)
                        rule(rec, [B + "/evaluate", timing],
                             "@mkdir -p $$(@D)",
                             "%s/evaluate -q %s %s %s --direction '%s' --motion %s --method %s --placement %s --training dense --out $$@"
                             % (B, seq, truth, feet[tgt], label, m, meth, default_pl))
                        results.append(rec)
                    if surf == "correct-stitch":
                        # Per-frame confidence beside the error (where truth exists), for the report.
                        plot = "%s/figures/confidence-%s-%s.png" % (out, dn, m)
                        has_truth = os.path.isdir(truth)
                        rule(plot, [B + "/paper-figure", timing] + ([rec] if has_truth else []),
                             "@mkdir -p $$(@D)",
                             "%s/paper-figure confidence -q --confidence %s/%s.json %s --title '%s %s: confidence and error per frame' --out $$@"
                             % (B, conf_dir, m, ("--eval " + rec) if has_truth else "", label, m))
                        stamps.append(plot)
                    sheet = "%s/render/%s/%s/%s/contact.png" % (out, dn, m, meth)
                    seqs = [os.path.join(set_dir, src, m), seq] + ([truth] if os.path.isdir(truth) else [])
                    rule(sheet, [B + "/render", timing],
                         "%s/render -q --separate-rows --no-frames --no-gif --labels source,%s%s --out $$(@D) %s"
                         % (B, meth, ",truth" if os.path.isdir(truth) else "", " ".join(seqs)))
                    stamps.append(sheet)
                sheet = "%s/render/%s/%s/contact.png" % (out, dn, m)
                seqs = [os.path.join(set_dir, src, m), "%s/transfer/%s/%s/gpr-nn" % (out, dn, m)]
                labels = "source,transfer"
                if os.path.isdir(truth):
                    seqs.append(truth)
                    labels += ",truth"
                rule(sheet, [B + "/render", "%s/predict/%s/%s/gpr-nn-%s.json" % (W, dn, m, default_pl)],
                     "%s/render -q --separate-rows --no-frames --no-gif --labels %s --out $$(@D) %s" % (B, labels, " ".join(seqs)))
                stamps.append(sheet)
# Learning curves (CVPR figs. 7-9) on the set's true correspondences, errors against the true
# parts (PCA truncation included), the paper's zero-mean GPs; the whole body at the parts' total
# dimensions (fitted by learning-curves itself).
true_pairs = " ".join("--true-pair %s %s/%s/%s.aligned %s/%s/%s.aligned" % (p["source"], W, S, p["source"], W, T, p["target"]) for p in spec["train"])
aligned_pairs = [a for p in spec["train"] for a in ("%s/%s/%s.aligned" % (W, S, p["source"]), "%s/%s/%s.aligned" % (W, T, p["target"]))]
lc = "%s/learning-curves/learning_curves.csv" % out
rule(lc, [B + "/learning-curves", os.path.join(set_dir, "set.json"), "%s/%s/pca.model" % (W, S), "%s/%s/pca.model" % (W, T)] + aligned_pairs,
     "@mkdir -p $$(@D)",
     "%s/learning-curves -q --seed 0 --mean zero --set %s --source-pca %s/%s/pca.model --target-pca %s/%s/pca.model --source-fps %g --target-fps %g --source-name %s --target-name %s %s --out $$(@D)"
     % (B, os.path.join(set_dir, "set.json"), W, S, W, T, fps[S], fps[T], S, T, true_pairs))
stamps.append(lc)
# CVPR fig. 3: the association cost of the first training pair, its DTW path, key-poses and truth.
p0 = spec["train"][0]
fig3 = "%s/figures/fig3-%s.png" % (out, p0["source"])
rule(fig3, [B + "/paper-figure", "%s/%s/pca.model" % (W, S), "%s/%s/pca.model" % (W, T), "%s/%s/%s.aligned" % (W, S, p0["source"]), "%s/%s/%s.aligned" % (W, T, p0["target"])],
     "@mkdir -p $$(@D)",
     "%s/paper-figure cost-matrix -q --set %s --pair %s --source-pca %s/%s/pca.model --target-pca %s/%s/pca.model %s/%s/%s.aligned %s/%s/%s.aligned --out $$@"
     % (B, os.path.join(set_dir, "set.json"), p0["source"], W, S, W, T, W, S, p0["source"], W, T, p0["target"]))
stamps.append(fig3)
# CVPR fig. 5 (a correction example) and fig. 10 (every method's raw output on one motion): the
# first forward test motion.
if directions[0][3]:
    m0 = directions[0][3][0]
    dn0 = "%s-to-%s" % (S, T)
    model0 = "%s/models/%s/gpr-nn.model" % (W, dn0)
    training = ["%s/%s/%s.aligned" % (W, T, t) for t in train[T]]
    truth0 = os.path.join(set_dir, "truth", T, m0)
    fig5 = "%s/figures/fig5-%s.png" % (out, m0)
    rule(fig5, [B + "/paper-figure", model0, "%s/%s/parts.seg" % (W, T), "%s/%s/%s.aligned" % (W, S, m0)] + training,
         "@mkdir -p $$(@D)",
         "%s/paper-figure correction -q --model %s --source-pca %s/%s/pca.model --target-pca %s/%s/pca.model --segmentation %s/%s/parts.seg %s %s --size 300 %s/%s/%s.aligned --out $$@ --report %s/figures/fig5-%s.json"
         % (B, model0, W, S, W, T, W, T, " ".join("--target-training " + t for t in training), ("--truth " + truth0) if os.path.isdir(truth0) else "", W, S, m0, out, m0))
    stamps.append(fig5)
    names = ["gpr-nn", "gpr-se", "gpr-linear", "keypose-affine", "whole-body", "gpr-nn-keyposes"]
    names = [n for n in names if n in methods or n == "gpr-nn-keyposes"]
    fig10 = "%s/figures/fig10-%s-%s/contact.png" % (out, dn0, m0)
    seqs = [os.path.join(set_dir, S, m0)] + ["%s/transfer/%s/%s/%s" % (out, dn0, m0, n) for n in names] + ([truth0] if os.path.isdir(truth0) else [])
    rule(fig10, [B + "/render"] + ["%s/predict/%s/%s/%s-%s.json" % (W, dn0, m0, n, default_pl) for n in names],
         "%s/render -q --separate-rows --no-frames --no-gif --follow --labels source,%s%s --out $$(@D) %s"
         % (B, ",".join(names), ",truth" if os.path.isdir(truth0) else "", " ".join(seqs)))
    stamps.append(fig10)

# The report's 3D view: the first forward test motion, after correction and stitching.
if directions[0][3]:
    m0 = directions[0][3][0]
    print("TRANSFER_REPORT_VIEWS := source=%s transfer=%s/transfer/%s-to-%s/%s/gpr-nn+correct+stitch truth=%s"
          % (os.path.join(set_dir, S, m0), out, S, T, m0, os.path.join(set_dir, "truth", T, m0)))
print("TRANSFER_RECORDS := " + " ".join(results))
print("TRANSFER_STAMPS := " + " ".join(stamps))
print()
print("\n".join(rules))
endef
export TRANSFER_RULES_PY

$(TRANSFER_RULES): $(SET)/set.json $(wildcard $(SET)/* $(SET)/truth/*) pipelines/transfer.mk
	@mkdir -p $(@D)
	@python3 -c "$$TRANSFER_RULES_PY" $(SET) $(OUT) "$(TRANSFER_METHODS)" $(PLACEMENT) $(PCA_COMPONENTS) > $@.tmp && mv $@.tmp $@


# The generated rules (and the merge below) exist only under `make transfer`, which calls
# `make transfer-results` once the binaries are built.
ifneq ($(filter transfer-results transfer-report,$(MAKECMDGOALS)),)
include $(TRANSFER_RULES)

# The run's HTML report (pipelines/report.mk), with source / transfer / truth in the 3D view.
transfer-report: $(OUT)/results.json
	@$(MAKE) --no-print-directory report OUT=$(OUT) REPORT_VIEWS="$(TRANSFER_REPORT_VIEWS)" REPORT_TITLE="surfcap transfer: $(SET)"

transfer-results: $(OUT)/results.json

# All evaluation records, merged into one list (sorted for a stable file).
$(OUT)/results.json: $(TRANSFER_RECORDS) $(TRANSFER_STAMPS)
	@python3 -c 'import json, sys; recs = [json.load(open(f)) for f in sys.argv[2:]]; recs.sort(key=lambda r: (r["direction"], r["motion"], r["method"], r.get("training", ""), r.get("placement", ""))); open(sys.argv[1] + ".tmp", "w").write(json.dumps(recs, indent=1) + "\n")' $@ $(TRANSFER_RECORDS)
	@mv $@.tmp $@
endif

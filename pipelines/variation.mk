# Variation synthesis (variation paper, issue 6):
#   make variation SET=<capture set> OUT=<dir>      (defaults: SET=$(OUT)/demo/set, OUT=out)
# Per movement group (VARIATION_GROUPS; motions in VARIATION_MOTIONS_<group>, missing ones skipped):
#   $(OUT)/work/variation/<group>.group       prealigned motions + pre-blended Y_w (prealign)
#   $(OUT)/work/variation/<group>.model       one GPDM per body part (gpdm-train)
#   $(OUT)/variation/<group>/<seq>/var<k>/    N variations of every training sequence and blend (hmc-sample)
#   $(OUT)/variation/render/<group>/<seq>/    variations overlaid in colours: contact.png, anim.gif
#   $(OUT)/variation/plots/<group>/           latent trajectories (figs. 3 and 5)
# and $(OUT)/variation.json (figures 4 and 7b, variation statistics, HMC acceptance).

SET ?= $(OUT)/demo/set
comma := ,
VARIATION_WORK := $(OUT)/work/variation
VARIATION_OUT := $(OUT)/variation
VARIATION_SUBJECT ?=
VARIATION_GROUPS ?= locomotion jump
VARIATION_MOTIONS_locomotion ?= walk,run
VARIATION_MOTIONS_jump ?= jump,cmu_jump
# Extra prealign flags per group: locomotion is cut to whole gait cycles before the DTW.
VARIATION_PREALIGN_FLAGS_locomotion ?= --gait-cycles
VARIATION_PREALIGN_FLAGS_jump ?=
VARIATION_W ?= 0.5
VARIATION_BLENDS ?= 0.25,0.75
VARIATION_N ?= 5
VARIATION_SEED ?= 0
# Scale of the sampled dynamics' one-step variances (hmc-sample --variance-scale; 1 = the model's
# density as in the paper). 0.3 keeps the variations' foot sliding and scatter near the captures'
# while they still differ from their source (docs/RESULTS.md, "Variance scale").
VARIATION_VARIANCE_SCALE ?= 0.3
VARIATION_TRAIN_FLAGS ?=
# The report's 3D view: three variations of the first group's first motion, side by side.
VARIATION_REPORT_GROUP := $(firstword $(VARIATION_GROUPS))
VARIATION_REPORT_MOTION := $(firstword $(subst $(comma), ,$(VARIATION_MOTIONS_$(VARIATION_REPORT_GROUP))))
VARIATION_REPORT_VIEWS ?= $(foreach k,0 1 2,var$(k)=$(VARIATION_OUT)/$(VARIATION_REPORT_GROUP)/$(VARIATION_REPORT_MOTION)/var$(k))
VARIATION_SAMPLE_FLAGS ?=

.PHONY: variation variation-results
variation:
	@test -f $(SET)/set.json || { echo "variation: $(SET)/set.json: no capture set (run 'make demo-data' or pass SET=<dir>)" >&2; exit 1; }
	$(CARGO) build --release --workspace --quiet
	@$(MAKE) --no-print-directory variation-results SET=$(SET) OUT=$(OUT)
	@$(MAKE) --no-print-directory report OUT=$(OUT) REPORT_VIEWS="$(VARIATION_REPORT_VIEWS)" REPORT_TITLE="surfcap variation: $(SET)"

variation-results: $(OUT)/variation.json

define VARIATION_GROUP_RULES
$(VARIATION_WORK)/$(1).group: $(SET)/set.json $(BIN)/prealign
	@mkdir -p $$(@D)
	$(BIN)/prealign -q --set $(SET) $(if $(VARIATION_SUBJECT),--subject $(VARIATION_SUBJECT)) --group $(1) --motions $(VARIATION_MOTIONS_$(1)) $(VARIATION_PREALIGN_FLAGS_$(1)) --blend-weights $(VARIATION_W) --out $$@

$(VARIATION_WORK)/$(1).model: $(VARIATION_WORK)/$(1).group $(BIN)/gpdm-train
	$(BIN)/gpdm-train -q $(VARIATION_TRAIN_FLAGS) $$< --out $$@ --report $(VARIATION_WORK)/$(1)-train.json

$(VARIATION_WORK)/$(1)-samples.json: $(VARIATION_WORK)/$(1).model $(BIN)/hmc-sample $(BIN)/render
	rm -rf $(VARIATION_OUT)/$(1) $(VARIATION_OUT)/render/$(1)
	$(BIN)/hmc-sample -q --seed $(VARIATION_SEED) -n $(VARIATION_N) --variance-scale $(VARIATION_VARIANCE_SCALE) --blends $(VARIATION_BLENDS) $(VARIATION_SAMPLE_FLAGS) --group $(VARIATION_WORK)/$(1).group $$< --out $(VARIATION_OUT)/$(1) --report $$@.tmp
	for d in $(VARIATION_OUT)/$(1)/*/; do s=$$$$(basename $$$$d); \
	  $(BIN)/render -q --no-frames --stride 2 --labels $$$$(cd $$$$d && ls -d var* | paste -sd,) --out $(VARIATION_OUT)/render/$(1)/$$$$s $$$$d/var*; done
	mv $$@.tmp $$@

$(VARIATION_WORK)/$(1)-eval.json: $(VARIATION_WORK)/$(1).model $(BIN)/variation-eval
	$(BIN)/variation-eval -q --seed $(VARIATION_SEED) --group $(VARIATION_WORK)/$(1).group $$< --plots $(VARIATION_OUT)/plots/$(1) --out $$@
endef
$(foreach g,$(VARIATION_GROUPS),$(eval $(call VARIATION_GROUP_RULES,$(g))))

VARIATION_RECORDS := $(foreach g,$(VARIATION_GROUPS),$(VARIATION_WORK)/$(g)-samples.json $(VARIATION_WORK)/$(g)-eval.json)

# One file with every group's training, evaluation and sampling records.
$(OUT)/variation.json: $(VARIATION_RECORDS)
	@python3 -c 'import json, sys; w = sys.argv[2]; gs = sys.argv[3:]; \
	  out = {g: {k: json.load(open("%s/%s-%s.json" % (w, g, k))) for k in ("train", "eval", "samples")} for g in gs}; \
	  open(sys.argv[1] + ".tmp", "w").write(json.dumps(out, indent=1) + "\n")' $@ $(VARIATION_WORK) $(VARIATION_GROUPS)
	@mv $@.tmp $@

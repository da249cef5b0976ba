# Motion transfer (transfer paper, sections 4 to 7; gpr-nn also runs gpr-predict --surface correct-stitch
# --corrected-out, i.e. section 6, recorded as methods gpr-nn+correct and gpr-nn+correct+stitch):
#   make transfer SET=<capture set> OUT=<dir>     (defaults: SET=$(OUT)/demo/set, OUT=out)
# Writes $(OUT)/transfer/<src>-to-<tgt>/<motion>/<method>/NNNNNN.ply, contact sheets under
# $(OUT)/render/, learning curves under $(OUT)/learning-curves/ and $(OUT)/results.json.
# Intermediate artifacts go to $(OUT)/work/. Every stage invocation is a rule of the task graph
# that `plan` writes from the capture set and the options below (pipelines/plan.mk). Idempotent
# (make's timestamps) and `make -j` safe.

SET ?= $(OUT)/demo/set
# Empty: the stage's own default (`<stage> --help`; docs/DEFAULTS.md).
# gpr-train --config of every model (default, affine-mean, no-prior, affine-only, zero-mean, auto, paper);
# paper also aligns on the whole body, places by the regressed displacement, drops the foot
# clean-ups and runs every method of the paper's comparison (CVPR §4-7)
CONFIG ?=
# Methods; empty: the configuration's (gpr-nn keypose-affine whole-body; paper adds gpr-se gpr-linear)
TRANSFER_METHODS ?=
# align --frame: root (poses fitted on the torso core) or body (the paper's whole mesh)
ALIGN_FRAME ?=
# pca-fit --part-alignment: body (parts cut from the aligned frames) or part (each part Procrustes-aligned)
PART_ALIGNMENT ?=
# gpr-predict --placement of every method's output (gpr-nn is also placed the other two ways)
PLACEMENT ?=
# gpr-train --mean: affine (least-squares affine map, GP on the residuals), zero (the paper) or
# both (the two GPs' average); empty: the configuration's (CONFIG; the default's is both)
GPR_MEAN ?=
# Further gpr-train flags for every model (e.g. --learn-noise, --nn-bias), and pca-fit --components
# per part (the whole body gets the parts' total)
GPR_TRAIN_FLAGS ?=
PCA_COMPONENTS ?=

.PHONY: transfer transfer-results transfer-report
transfer: $(STAGE_BINARIES)
	@test -f $(SET)/set.json || { echo "transfer: $(SET)/set.json: no capture set (run 'make demo' or pass SET=<dir>)" >&2; exit 1; }
	@$(MAKE) --no-print-directory $(PIPELINE_JOBS) transfer-results SET=$(SET) OUT=$(OUT)
	@$(MAKE) --no-print-directory transfer-report SET=$(SET) OUT=$(OUT)
	@$(MAKE) --no-print-directory export SET=$(SET) OUT=$(OUT)

# The run's HTML report (pipelines/report.mk), with source / transfer / truth in the 3D view. The
# rules of every stage invocation, results.json's among them, are the task graph that
# pipelines/plan.mk includes under these goals.
transfer-report: $(OUT)/results.json
	@$(MAKE) --no-print-directory report OUT=$(OUT) REPORT_VIEWS="$(TRANSFER_REPORT_VIEWS)" REPORT_TITLE="surfcap transfer: $(SET)"

transfer-results: $(OUT)/results.json

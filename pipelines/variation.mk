# Variation synthesis (3DV paper):
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
VARIATION_OUT := $(OUT)/variation
# Options (unset: crates/plan's defaults, `plan make --help`): VARIATION_SUBJECT (the set's
# source), VARIATION_GROUPS (locomotion jump) with VARIATION_MOTIONS_<group>
# (walk,run,turn_left,turn_right; jump,cmu_jump; a set's missing motions are left out) and VARIATION_PREALIGN_FLAGS_<group> (locomotion: --gait-cycles, cut to whole
# gait cycles before the DTW), VARIATION_W (prealign --blend-weights, 0.5), VARIATION_BLENDS
# (hmc-sample --blends, 0.25,0.75), VARIATION_N (variations per sequence, 5), VARIATION_SEED (0),
# VARIATION_VARIANCE_SCALE (hmc-sample's own default), VARIATION_TRAIN_FLAGS and
# VARIATION_SAMPLE_FLAGS (further gpdm-train and hmc-sample flags). A group may hold more motions
# and pre-blend several pairs at several weights, e.g.
#   VARIATION_GROUPS=moves VARIATION_MOTIONS_moves=walk,run,kick VARIATION_W=0.25,0.5,0.75 \
#   VARIATION_PREALIGN_FLAGS_moves="--blend-pairs walk:run,run:kick"
# (the first pair is the one --blends and fig. 7b use; a group of one motion is sampled without
# blends). The report's 3D view (VARIATION_REPORT_VIEWS, from the plan) shows three variations of
# the first group's first motion.
VARIATION_SUBJECT ?=
VARIATION_GROUPS ?=
VARIATION_W ?=
VARIATION_BLENDS ?=
VARIATION_N ?=
VARIATION_SEED ?=
VARIATION_VARIANCE_SCALE ?=
VARIATION_TRAIN_FLAGS ?=
VARIATION_SAMPLE_FLAGS ?=

.PHONY: variation variation-results variation-report
variation: $(STAGE_BINARIES)
	@test -f $(SET)/set.json || { echo "variation: $(SET)/set.json: no capture set (run 'make demo-data' or pass SET=<dir>)" >&2; exit 1; }
	@$(MAKE) --no-print-directory $(PIPELINE_JOBS) variation-results SET=$(SET) OUT=$(OUT)
	@$(MAKE) --no-print-directory variation-report SET=$(SET) OUT=$(OUT)
	@$(MAKE) --no-print-directory export SET=$(SET) OUT=$(OUT)

# The run's HTML report (pipelines/report.mk) with three variations in the 3D view.
variation-report: $(OUT)/variation.json
	@$(MAKE) --no-print-directory report OUT=$(OUT) REPORT_VIEWS="$(VARIATION_REPORT_VIEWS)" REPORT_TITLE="surfcap variation: $(SET)"

# The rules (prealign, gpdm-train, hmc-sample and its contact sheets, variation-eval per group,
# then variation.json) are the task graph that pipelines/plan.mk includes under this goal.
variation-results: $(OUT)/variation.json

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
VARIATION_SUBJECT ?=
VARIATION_GROUPS ?= locomotion jump
VARIATION_MOTIONS_locomotion ?= walk,run
VARIATION_MOTIONS_jump ?= jump,cmu_jump
# A group may hold more motions and pre-blend several pairs at several weights, e.g.
#   VARIATION_GROUPS=moves VARIATION_MOTIONS_moves=walk,run,kick VARIATION_W=0.25,0.5,0.75 \
#   VARIATION_PREALIGN_FLAGS_moves="--blend-pairs walk:run,run:kick"
# (VARIATION_W is prealign --blend-weights; the first pair is the one --blends and fig. 7b use;
# a group of one motion is sampled without blends.)
# Extra prealign flags per group: locomotion is cut to whole gait cycles before the DTW.
VARIATION_PREALIGN_FLAGS_locomotion ?= --gait-cycles
VARIATION_PREALIGN_FLAGS_jump ?=
VARIATION_W ?= 0.5
VARIATION_BLENDS ?= 0.25,0.75
VARIATION_N ?= 5
VARIATION_SEED ?= 0
# Scale of the sampled dynamics' one-step variances (hmc-sample --variance-scale; 1 = the model's
# density as in the paper). 0.3 keeps the variations' foot sliding and scatter near the captures'
# while they still differ from their source (docs/studies/14-variance-scale.md).
VARIATION_VARIANCE_SCALE ?= 0.3
VARIATION_TRAIN_FLAGS ?=
# The report's 3D view: three variations of the first group's first motion, side by side.
VARIATION_REPORT_GROUP := $(firstword $(VARIATION_GROUPS))
VARIATION_REPORT_MOTION := $(firstword $(subst $(comma), ,$(VARIATION_MOTIONS_$(VARIATION_REPORT_GROUP))))
VARIATION_REPORT_VIEWS ?= $(foreach k,0 1 2,var$(k)=$(VARIATION_OUT)/$(VARIATION_REPORT_GROUP)/$(VARIATION_REPORT_MOTION)/var$(k))
VARIATION_SAMPLE_FLAGS ?=

.PHONY: variation variation-results
variation: $(STAGE_BINARIES)
	@test -f $(SET)/set.json || { echo "variation: $(SET)/set.json: no capture set (run 'make demo-data' or pass SET=<dir>)" >&2; exit 1; }
	@$(MAKE) --no-print-directory variation-results SET=$(SET) OUT=$(OUT)
	@$(MAKE) --no-print-directory report OUT=$(OUT) REPORT_VIEWS="$(VARIATION_REPORT_VIEWS)" REPORT_TITLE="surfcap variation: $(SET)"
	@$(MAKE) --no-print-directory export SET=$(SET) OUT=$(OUT)

# The rules (prealign, gpdm-train, hmc-sample and its contact sheets, variation-eval per group,
# then variation.json) are the task graph that pipelines/plan.mk includes under this goal.
variation-results: $(OUT)/variation.json

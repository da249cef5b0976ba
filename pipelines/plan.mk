# The pipelines' task graph (crates/plan). `check-set` validates the capture set first (every
# problem one line, exit 1), then `plan make` writes every stage invocation of
# `make transfer` and `make variation` (target, inputs, recipe) into $(PLAN_MK) from the capture
# set and the options of pipelines/transfer.mk and pipelines/variation.mk; the pipelines' result
# goals include it. It is rewritten when the set's description or folders, the plan binary or the
# options change (the options are kept in $(PLAN_OPTIONS), rewritten only when they differ).
#   make slurm SET=<capture set> OUT=<dir>     Slurm job arrays of both pipelines: sbatch <dir>/run.sbatch
#     SLURM_RESOURCES=<file>: measured peaks per stage (scripts/slurm-measure) for --mem/--cpus-per-task
# The top-level Makefile includes this file after the pipelines, so that every option is defined.

PLAN_MK := $(OUT)/work/plan.mk
PLAN_OPTIONS := $(OUT)/work/plan.options
PLAN_GOALS := transfer-results transfer-report variation-results variation-report
PLAN_ARGS := --set $(SET) --pipeline-out $(OUT) \
  $(if $(CONFIG),--config $(CONFIG)) $(if $(TRANSFER_METHODS),--methods $(TRANSFER_METHODS)) \
  $(if $(ALIGN_FRAME),--align-frame $(ALIGN_FRAME)) \
  $(if $(PART_ALIGNMENT),--part-alignment $(PART_ALIGNMENT)) $(if $(PLACEMENT),--placement $(PLACEMENT)) \
  $(if $(GPR_MEAN),--gpr-mean $(GPR_MEAN)) --gpr-train-flags '$(GPR_TRAIN_FLAGS)' \
  $(if $(PCA_COMPONENTS),--pca-components $(PCA_COMPONENTS)) $(if $(VARIATION_SUBJECT),--variation-subject $(VARIATION_SUBJECT)) \
  $(foreach g,$(VARIATION_GROUPS),--variation-group $(g)=$(VARIATION_MOTIONS_$(g)) \
    $(if $(VARIATION_PREALIGN_FLAGS_$(g)),'--prealign-flags=$(g)=$(VARIATION_PREALIGN_FLAGS_$(g))')) \
  $(if $(VARIATION_W),--variation-w $(VARIATION_W)) $(if $(VARIATION_BLENDS),--variation-blends $(VARIATION_BLENDS)) \
  $(if $(VARIATION_N),--variation-n $(VARIATION_N)) $(if $(VARIATION_SEED),--variation-seed $(VARIATION_SEED)) \
  $(if $(VARIATION_VARIANCE_SCALE),--variation-variance-scale $(VARIATION_VARIANCE_SCALE)) \
  --variation-train-flags '$(VARIATION_TRAIN_FLAGS)' --variation-sample-flags '$(VARIATION_SAMPLE_FLAGS)'

# PART_TASKS=1: make runs Slurm's split (one task per part of each model of several parts and
# their merges; scripts/slurm-measure) instead of one task per model.
PART_TASKS ?=
MAKE_PLAN_ARGS := $(PLAN_ARGS) $(if $(PART_TASKS),--part-tasks)

ifneq ($(filter $(PLAN_GOALS),$(MAKECMDGOALS)),)
ifneq ($(file <$(PLAN_OPTIONS)),$(strip $(MAKE_PLAN_ARGS)))
$(shell mkdir -p $(dir $(PLAN_OPTIONS)))
$(file >$(PLAN_OPTIONS),$(strip $(MAKE_PLAN_ARGS)))
endif

$(PLAN_MK): $(PLAN_OPTIONS) $(BIN)/plan $(BIN)/check-set $(SET)/set.json $(wildcard $(SET)/* $(SET)/*/* $(SET)/truth/*)
	@$(BIN)/check-set $(SET)
	$(BIN)/plan make -q $(MAKE_PLAN_ARGS) --out $@

include $(PLAN_MK)
else ifneq ($(filter export,$(MAKECMDGOALS)),)
# `make export` reads the plan of the run it exports (VARIATION_REPORT_VIEWS), never remakes it.
-include $(PLAN_MK)
endif

SLURM_RESOURCES ?=
.PHONY: slurm
slurm: $(STAGE_BINARIES)
	@test -f $(SET)/set.json || { echo "slurm: $(SET)/set.json: no capture set (run 'make demo-data' or pass SET=<dir>)" >&2; exit 1; }
	@$(BIN)/check-set $(SET)
	$(BIN)/plan slurm -q $(PLAN_ARGS) --bin $(BIN) $(if $(SLURM_RESOURCES),--resources $(SLURM_RESOURCES)) --out $(OUT)

# make demo: the main job on the default data, from nothing:
#   fetch the real assets, build, synthesise the demo capture set (out/demo/set), render it
#   (out/demo/render/<subject>/<motion>/{contact.png,anim.gif}), then run the transfer and variation
#   pipelines on it; each ends with the HTML report out/index.html (transfer last, so its 3D view
#   shows source / transfer / truth; the page lists the variation results too).
# `make demo-data` / `make demo-render` stop earlier. `make holdout-data` builds the second
# benchmark set (out/holdout/set: other bodies, styles, rates and test clips; nothing is tuned on it);
# `make outside-data` a third (out/outside/set), measured with the defaults and never tuned on;
# `make turning-data` the demo set with a left and a right turning walk (out/turning/set): the 3DV
# paper's four-sequence locomotion group for `make variation SET=out/turning/set`.
DEMO := $(OUT)/demo
DEMO_SET := $(DEMO)/set
SEED ?= 0

.PHONY: demo demo-data demo-render holdout-data outside-data turning-data
HOLDOUT_SET := $(OUT)/holdout/set
OUTSIDE_SET := $(OUT)/outside/set
TURNING_SET := $(OUT)/turning/set

demo: demo-render
	@$(MAKE) --no-print-directory variation SET=$(DEMO_SET) OUT=$(OUT)
	@$(MAKE) --no-print-directory transfer SET=$(DEMO_SET) OUT=$(OUT)
	@echo "demo: open $(OUT)/index.html (report), $(DEMO)/render/ (the captures)" >&2

demo-data: $(DEMO_SET)/set.json

$(DEMO_SET)/set.json: | build assets
	$(BIN)/synth -q --seed $(SEED) --out $(DEMO_SET)

# One contact sheet + GIF per motion of each subject (renders in parallel with make -j).
demo-render: demo-data
	@$(MAKE) --no-print-directory -f pipelines/render-set.mk SET=$(DEMO_SET) RENDER=$(DEMO)/render BIN=$(BIN)

holdout-data: $(HOLDOUT_SET)/set.json

$(HOLDOUT_SET)/set.json: | build assets
	$(BIN)/synth -q --preset holdout --seed $(SEED) --out $(HOLDOUT_SET)

outside-data: $(OUTSIDE_SET)/set.json

$(OUTSIDE_SET)/set.json: | build assets
	$(BIN)/synth -q --preset outside --seed $(SEED) --out $(OUTSIDE_SET)

turning-data: $(TURNING_SET)/set.json

$(TURNING_SET)/set.json: | build assets
	$(BIN)/synth -q --preset turning --seed $(SEED) --out $(TURNING_SET)

# make demo: fetch real assets, build, synthesise the default capture set and render it.
#   out/demo/set/                 the capture set (docs/FORMATS.md)
#   out/demo/render/<subject>/<motion>/{contact.png,anim.gif}
DEMO := $(OUT)/demo
DEMO_SET := $(DEMO)/set
SEED ?= 0

.PHONY: demo demo-data demo-render

demo: demo-render

demo-data: $(DEMO_SET)/set.json

$(DEMO_SET)/set.json: | build assets
	$(BIN)/synth -q --seed $(SEED) $(DEMO_SET)

# One contact sheet + GIF per training motion of each subject (renders in parallel with make -j).
demo-render: demo-data
	@$(MAKE) --no-print-directory -f pipelines/render-set.mk SET=$(DEMO_SET) RENDER=$(DEMO)/render BIN=$(BIN)

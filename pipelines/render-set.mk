# Renders every motion folder of a capture set: $(RENDER)/<subject>/<motion>/{contact.png,anim.gif}.
# Called by demo.mk once the set exists (the list of motions is only known then).
SET ?= out/demo/set
RENDER ?= out/demo/render
BIN ?= target/release
SHELL := bash

MOTIONS := $(patsubst $(SET)/%/000000.ply,%,$(wildcard $(SET)/*/*/000000.ply))
TARGETS := $(foreach m,$(MOTIONS),$(RENDER)/$(m)/contact.png)

all: $(TARGETS)

$(RENDER)/%/contact.png: $(SET)/%/000000.ply
	$(BIN)/render -q --no-frames --follow --labels $(subst /,-,$*) --subject $(SET)/$(firstword $(subst /, ,$*))/subject.json --out $(@D) $(SET)/$*

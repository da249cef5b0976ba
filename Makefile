# surfcap: top-level entry points. Pipelines live in pipelines/*.mk.
#   make demo   fetch the real assets, build, synthesise the demo capture set, render it
#   make test   the whole test suite (release mode: the numerics need it)
#   make build  release build of every stage binary

SHELL := bash
.SHELLFLAGS := -eu -o pipefail -c
.DELETE_ON_ERROR:
MAKEFLAGS += --no-builtin-rules

CARGO ?= cargo
BIN := target/release
OUT ?= out
SURFCAP_CACHE ?= $(HOME)/.cache/surfcap
export SURFCAP_CACHE
# rayon does the parallelism; OpenBLAS threads would fight it (see docs/PERFORMANCE.md).
export OPENBLAS_NUM_THREADS := 1

.PHONY: all build test setup assets clean-out help
all: build

help:
	@sed -n '2,5p' Makefile

setup:
	@scripts/setup-system

build: setup
	$(CARGO) build --release --workspace --quiet

# assets: synth's tests use the real bodies; setup-web: glTF validator + headless Chromium tests.
test: build assets setup-web
	$(CARGO) test --release --workspace

clean-out:
	rm -rf $(OUT)

# The pipelines, then their task graph (pipelines/plan.mk reads every pipeline's options).
include $(filter-out pipelines/plan.mk,$(wildcard pipelines/*.mk))
include pipelines/plan.mk

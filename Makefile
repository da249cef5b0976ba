# surfcap: top-level entry points. Pipelines live in pipelines/*.mk.
#   make demo   fetch the real assets, build, synthesise the demo capture set, render it
#   make test   the whole test suite (release mode: the numerics need it)
#   make build  release build of every stage binary
#   make slurm SET=<set> OUT=<dir>   both pipelines as Slurm job arrays: sbatch <dir>/run.sbatch

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
	@sed -n '2,6p' Makefile

setup:
	@scripts/setup-system

build: setup
	$(CARGO) build --release --workspace --quiet

# assets: synth's tests use the real bodies; setup-web: glTF validator + headless Chromium tests;
# scripts/slurm-test installs Slurm + munge and runs the tiny preset's pipelines as job arrays.
test: build assets setup-web
	$(CARGO) test --release --workspace
	scripts/slurm-test

clean-out:
	rm -rf $(OUT)

# The pipelines, then their task graph (pipelines/plan.mk reads every pipeline's options).
include $(filter-out pipelines/plan.mk,$(wildcard pipelines/*.mk))
include pipelines/plan.mk

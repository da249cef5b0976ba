# surfcap: top-level entry points. Pipelines live in pipelines/*.mk.
#   make demo   fetch the real assets, build, synthesise the demo capture set, render it, run both pipelines
#   make test   the whole test suite (release mode: the numerics need it)
#   make build  release build of every stage binary
#   make slurm SET=<set> OUT=<dir>   both pipelines as Slurm job arrays: sbatch <dir>/run.sbatch
#   make transfer SET=<set> OUT=<dir>   the transfer pipeline (CVPR 2017), results.json + report
#   make variation SET=<set> OUT=<dir>  the variation pipeline (3DV 2017), variation.json + report
#   make demo-data | holdout-data | outside-data | turning-data   synthesise a benchmark capture set (out/...)
#   make characters-data   capture sets from real animated game characters (out/characters/...)
#   make demo-render   contact sheets and GIFs of the demo set
#   make report OUT=<dir>   the HTML report of a run;  make assets   fetch the real bodies and mocap
#   make export OUT=<dir>   .glb and OBJ + PC2 of a run's final transfers and the report's variations
#   make setup | setup-web   system packages (OpenBLAS) / the report tests' web tools (Chromium)
#   make man | completions   man pages / bash, zsh, fish completions of every stage: target/man, target/completions
#   make clean-out   remove $(OUT);  make help   this list
#   NO_BUILD=1   the pipelines use the binaries as built (no check that the sources are older)
#   JOBS=N   stage invocations the pipelines run side by side (default: the machine's cores)

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
# glibc's malloc backs its large blocks with transparent huge pages (glibc 2.35 and later; older
# ones ignore it): first touches of fresh memory (page faults) were a quarter of make transfer's
# CPU time; the outputs are the same bytes (docs/PERFORMANCE.md).
export GLIBC_TUNABLES ?= glibc.malloc.hugetlb=1
# The pipelines run JOBS stage invocations side by side (their task graph's independent steps;
# each stage's own threads share the cores), unless make was given its own -j: JOBS=1 runs them
# one at a time.
JOBS ?= $(shell nproc 2>/dev/null || echo 1)
PIPELINE_JOBS = $(if $(findstring jobserver,$(MAKEFLAGS)),,-j$(JOBS))

.PHONY: all build test setup assets clean-out help man completions
all: build

help:
	@sed -n '2,16p' Makefile
	@echo "Stages: $(BIN)/surfcap help (after make build)"

# Generated from every stage's clap definition (surfcap man / completions).
man completions: build
	$(BIN)/surfcap $@ --out target/$@

setup:
	@scripts/setup-system

# The research programs (crate studies) are left out: `cargo build --release -p studies` builds
# them, and `make test` compiles them in test mode.
build: setup
	$(CARGO) build --release --workspace --exclude studies --quiet
	@touch $(BUILD_STAMP)

# The pipelines build the stage binaries only when a source is newer than the last build;
# NO_BUILD=1 skips the check (binaries built otherwise, or a read-only checkout on a cluster).
BUILD_STAMP := $(BIN)/.build-stamp
$(BUILD_STAMP): Cargo.toml Cargo.lock $(shell find crates -path '*/src/*' -name '*.rs' -o -name Cargo.toml) | setup
	@echo "make: building the stage binaries (sources changed; NO_BUILD=1 skips this)" >&2
	$(CARGO) build --release --workspace --exclude studies --quiet
	@touch $@
STAGE_BINARIES := $(if $(NO_BUILD),,$(BUILD_STAMP))

# assets: synth's tests use the real bodies; setup-web: glTF validator + headless Chromium tests;
# scripts/slurm-test installs Slurm + munge and runs the tiny preset's pipelines as job arrays.
# scripts/usd-check reads the .usda export back with usd-core and Blender (PyPI bpy, Python 3.11);
# scripts/alembic-check reads Blender's Alembic export of a sequence back with mesh-import.
test: build assets setup-web
	scripts/check-doc-links
	$(CARGO) test --release --workspace
	scripts/blender-check
	scripts/usd-check
	scripts/alembic-check
	scripts/slurm-test

clean-out:
	rm -rf $(OUT)

# The pipelines, then their task graph (pipelines/plan.mk reads every pipeline's options).
include $(filter-out pipelines/plan.mk,$(wildcard pipelines/*.mk))
include pipelines/plan.mk

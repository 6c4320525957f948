# SPDX-License-Identifier: MIT
# stepramp: the two commands are `make demo` and `make test` (a plain `make` runs the regression).
# Each sets up what it needs (.venv with pinned packages, GHDL) through scripts/bootstrap.sh.

SHELL := /bin/bash
VENV  := .venv
PY    := $(VENV)/bin/python
JOBS  ?= auto
VHDL  := $(wildcard hdl/*.vhd)
# The LLVM back end runs simulations about twice as fast: bootstrap installs it when it can, and the recipes
# pick it when it is there (decided when the recipe runs, after bootstrap). GHDL_BACKEND=mcode make test forces.
BACKEND = GHDL_BACKEND=$${GHDL_BACKEND:-$$(test -x /usr/bin/ghdl-llvm && echo llvm || echo mcode)}
# Python keeps the byte code it compiles (in __pycache__, which git ignores) even where the caller's environment says
# PYTHONDONTWRITEBYTECODE: without it, each of the regression's ~150 simulations parsed the package, the benches and
# pytest's assertion rewrites from source again (about 0.2 s of CPU each).
unexport PYTHONDONTWRITEBYTECODE

.DEFAULT_GOAL := test
.PHONY: setup prefetch test check coverage mutate soak lint synth-check bench synth demo shell waves vitis-driver clean help

help:
	@echo "make test         lint, synthesis check and the whole regression (pytest -n $(JOBS))"
	@echo "make check        the quick tier for inner loops (about 2 min): lint, the model and driver tests, the unit benches"
	@echo "make coverage     the regression, then its functional coverage report (build/coverage/report.md)"
	@echo "make mutate       mutation check of the RTL (MUTANTS=80 SEED=1): killed / valid / total and the survivors"
	@echo "make soak         random soak on both tops (SECONDS=60 SEED=1; OPS=K replays the first K operations)"
	@echo "make demo         simulate the AVR446 demo move on the RTL, write build/demo/"
	@echo "make waves        open the demo's waveform laid out (GTKWave; else Surfer; else print the command)"
	@echo "make shell        the AVR446 demo's command shell on the simulated core (type ? for help)"
	@echo "make lint         ruff check, ruff format --check, vsg"
	@echo "make synth-check  every RTL file under --std=93c and --std=08, ghdl synth of each top, no latch"
	@echo "make bench        the change latency of CTRL.CHANGE per ramp phase, and the simulation speed (clocks/s)"
	@echo "make synth        size and fmax: yosys iCE40 / xc7, nextpnr HX8K / UP5K -> build/synth/report.json"
	@echo "make vitis-driver the Vitis driver folder (drivers/stepramp_v1_0 + sw/c/src) in build/vitis/drivers/"
	@echo "make clean        remove build/ and the byte code caches (keeps .venv)"

setup:
	@scripts/bootstrap.sh $(VENV)

lint: setup
	$(VENV)/bin/ruff check sw tb scripts
	$(VENV)/bin/ruff format --check sw tb scripts
	$(VENV)/bin/vsg -c vsg.yaml -f $(VHDL) -ap -of summary

synth-check: setup
	$(PY) -m stepramp.tools.rtlcheck --out build/synth_check

# Every simulation of the regression writes its functional coverage to build/coverage (stepramp.sim.coverage); the
# regression fails when a bin stays empty. The random scripts run on a fixed seed here (SCRIPT_SEED=1 unless given),
# so that a red run names its cause and replays; pytest alone draws a fresh seed and prints it. The workers take the
# tests longest first, each sw/tests module as one unit (tb/conftest.py), so that they end together.
COVERAGE := build/coverage
DIST     := --dist loadgroup --no-loadscope-reorder
test: prefetch lint
	rm -rf $(COVERAGE)
	STEPRAMP_COVERAGE_DIR=$(CURDIR)/$(COVERAGE) SCRIPT_SEED=$${SCRIPT_SEED:-1} $(BACKEND) \
	  $(PY) -m pytest -n $(JOBS) $(DIST) -rA --durations=25
	$(PY) -m stepramp.tools.coverage $(COVERAGE) --check

# The size check's yosys run (tb/test_synth_size.py: about 45 s of one core) starts in the background before the
# bootstrap and the lint, which leave a core idle; the test finds its result in the content-keyed cache (or waits for
# it on the cache's lock; it runs it itself if this did not). Where GHDL or yosys is still missing, the bootstrap
# starts it once it has installed them (scripts/prefetch.sh).
prefetch:
	@scripts/prefetch.sh

# The quick tier for inner loops, never instead of `make test`: lint, every sw/tests test (the model, the planner, the
# drivers, the tools) and the RTL's unit benches (prio_enc, timer, divider, next_delay: seconds each).
CHECK := sw/tests tb/test_prio_enc.py tb/test_timer.py tb/test_divider.py tb/test_next_delay.py
check: lint
	$(BACKEND) $(PY) -m pytest -n $(JOBS) $(DIST) -q -p no:cacheprovider --durations=5 $(CHECK)

coverage: test
	@cat $(COVERAGE)/report.md

# Mutation check (not part of `make test`): MUTANTS mutants of the RTL drawn with SEED, each against its quick suite.
MUTANTS ?= 80
SEED    ?= 1
mutate: setup
	$(BACKEND) $(PY) -m stepramp.tools.mutate --sample $(MUTANTS) --seed $(SEED)

# Random soak on both tops: SECONDS of wall time each (or OPS operations), seeded; a failing seed replays exactly.
SECONDS ?= 60
OPS     ?= 0
soak: setup
	SOAK_SEED=$(SEED) SOAK_SECONDS=$(if $(filter 0,$(OPS)),$(SECONDS),0) SOAK_OPS=$(OPS) \
	  $(BACKEND) $(PY) -m pytest -n 2 -q -rA -p no:cacheprovider tb/test_soak.py | grep -E "^soak|passed|failed|Error|replay"; test $${PIPESTATUS[0]} = 0

# Figures no test asserts: the change latency of CTRL.CHANGE per phase (from the driver's planner), then the
# simulation speed in clocks/s during a move on the engine bench, each bus top and each multi-axis top.
bench: setup
	$(PY) -m stepramp.tools.changebench
	$(BACKEND) $(PY) -m stepramp.tools.simbench

synth:
	@scripts/bootstrap.sh $(VENV) synth
	$(PY) -m stepramp.tools.synth --out build/synth

demo: setup
	$(BACKEND) $(PY) -m stepramp.tools.demo --out build/demo

shell: setup
	$(BACKEND) $(VENV)/bin/stepramp shell

WAVE := build/demo/stepramp_demo.ghw
GTKW := build/demo/stepramp_demo.gtkw
waves:
	@test -f $(GTKW) || $(MAKE) demo
	@if command -v gtkwave >/dev/null 2>&1; then gtkwave $(GTKW); \
	elif command -v surfer >/dev/null 2>&1; then surfer $(WAVE); \
	else echo "no viewer here: open the laid-out view with  gtkwave $(GTKW)  (or the raw waveform: surfer $(WAVE))"; fi

vitis-driver: setup
	$(PY) -m stepramp.tools.vitis_driver

clean:
	rm -rf build .pytest_cache
	find sw tb scripts -name __pycache__ -prune -exec rm -rf {} +

# touchbench: the two commands of the README, and the paper reproduction.
#   make demo              set up .venv with touchbench alone (no extras) and run the main job
#   make test              set up .venv (with the dev, deep, dist, peers and xgboost-cpu extras and the
#                          example plugin) and run the tests, spread over TEST_WORKERS processes
#                          (pytest-xdist; TEST_WORKERS=1: one process)
#   make lint              check every function of touchbench/: at most 80 lines, cyclomatic
#                          complexity at most 15, no unused import (flake8, configured in pyproject.toml)
#   make api-docs          build the API reference (pdoc) into build/api; any warning fails
#   make snapshots         record the names every registry holds (tests/snapshots/), after adding an entry
#   make reproduce-papers  run touchbench/protocols/papers/ and write results/papers/REPORT.md
#   make examples          run the example protocols on real HAART and regenerate the example
#                          leaderboards and report (results/examples/) and their figures in the
#                          README (docs/figures/, stable names); the touch methods' are touch-all's
#   make touch-all         every method of touch-all under its seven evaluations (hours on two cores:
#                          QUANT and RDST; METHODS="--method touch-et --method minirocket" runs some),
#                          then its leaderboard (results/touch-all/) and the README's figures
#   make touch-all-figures the leaderboard and figures alone, from the finished tasks
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
EXTRAS ?= dev,deep,dist,peers,xgboost-cpu
# pins for the development and CI environments only (users get pyproject.toml's ranges)
CONSTRAINTS := constraints.txt
PROFILE ?= quick
# Test processes (pytest-xdist -n): one per CPU this process may run on (its affinity, so a container
# or `taskset` limit counts; xdist's `-n auto` counts the machine's physical cores), at most 8: every
# worker holds about 1 GB (torch, aeon) and many tests start two processes of their own. TEST_WORKERS=1:
# the tests run in pytest's own process (-n 0), no worker started.
TEST_WORKERS ?= $(shell $(PYTHON) -c "import os; n = len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else os.cpu_count(); print(min(8, n or 1))")
JOBS ?= 2
RUNS ?= results/runs
TB := $(BIN)/touchbench

.PHONY: setup demo test lint api-docs snapshots reproduce-papers examples reference-results touch-all touch-all-figures clean

PLUGIN := examples/touchbench-plugin-example

# One stamp per set of extras: .installed-core (touchbench alone: `make demo`) or
# .installed-dev,deep,... (`make setup`).
$(VENV)/.installed-%: pyproject.toml $(CONSTRAINTS)
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -c $(CONSTRAINTS) -e ".$(if $(filter core,$*),,[$*])"
	touch $@

# The example plugin is installed as users install one (not editable): the tests run it by name.
# tsml-eval's loader reads our `touchbench export --format tsml` files back in the tests; it is
# installed without its dependencies: its pins (aeon<1.2, scikit-learn<1.7) would downgrade ours,
# and its results loader needs none of them beyond what the peers extra has.
$(VENV)/.plugin: $(VENV)/.installed-$(EXTRAS) $(PLUGIN)/pyproject.toml $(wildcard $(PLUGIN)/src/*/*.py)
	$(BIN)/python -m pip install -q -c $(CONSTRAINTS) ./$(PLUGIN)
	$(BIN)/python -m pip install -q -c $(CONSTRAINTS) --no-deps "tsml-eval==0.6.0"
	touch $@

setup: $(VENV)/.installed-$(EXTRAS) $(VENV)/.plugin

demo: $(VENV)/.installed-core
	$(BIN)/touchbench demo --jobs $(JOBS)

test: setup
	$(BIN)/python -m pytest -q -p no:cacheprovider -n $(if $(filter 1,$(TEST_WORKERS)),0,$(TEST_WORKERS)) --dist loadgroup

lint: setup
	$(BIN)/flake8 touchbench

api-docs: setup
	$(BIN)/python docs/build_api_docs.py build/api

snapshots: setup
	$(BIN)/python tests/snapshots/registries.py

reproduce-papers: setup
	$(BIN)/touchbench papers reproduce --profile $(PROFILE) --jobs $(JOBS) --audit

examples: setup
	$(TB) run example-haart-loso --out $(RUNS)/example-haart-loso --jobs $(JOBS) --no-progress
	$(TB) run example-haart-early --out $(RUNS)/example-haart-early --jobs $(JOBS) --no-progress
	$(TB) leaderboard $(RUNS)/example-haart-loso $(RUNS)/example-haart-early --out results/examples \
	    --format md --format csv --format json
	$(TB) report $(RUNS)/example-haart-loso $(RUNS)/example-haart-early --out results/examples \
	    --title "touchbench example: real HAART, leave-one-subject-out"
	$(TB) plot $(RUNS)/example-haart-loso --out docs/figures --name example-haart-loso --format png --format svg \
	    --kind pareto --kind confusion --reference "Gaus 2015 challenge=66.5"

TOUCH_ALL := $(RUNS)/touch-all
# the shipped reference results (`touchbench reference list`; `leaderboard --reference NAME`):
# each protocol run afresh, then saved into the package under its own name (explicitly: `reference save`
# writes into the user's folder of references by default, and replaces one only with --force)
REFERENCES ?= tiny demo-haart haart-loso-msd-rf stream-haart stream-scene stream-table stream-skin
reference-results: setup
	@for p in $(REFERENCES); do \
	    rm -rf $(RUNS)/reference/$$p && \
	    $(TB) run $$p --out $(RUNS)/reference/$$p --jobs $(JOBS) --no-progress && \
	    $(TB) reference save $(RUNS)/reference/$$p --name $$p --to touchbench/data/reference --force || exit 1; \
	done

touch-all: setup
	$(TB) run touch-all --out $(TOUCH_ALL) --jobs $(JOBS) --no-progress $(METHODS)
	$(MAKE) touch-all-figures

touch-all-figures: setup
	$(TB) leaderboard $(TOUCH_ALL) --out results/touch-all --format md --format csv
	$(TB) plot $(TOUCH_ALL)/loso --out docs/figures --kind pareto --name touch-all-loso \
	    --format png --format svg --reference "Al-mashhadani 2021 CNN=83.2" --reference "target=84"
	$(TB) plot $(TOUCH_ALL)/challenge --out docs/figures --kind pareto --name touch-all-challenge \
	    --format png --format svg --reference "best 2015 entry=70.9" --reference "target=80"
	$(TB) plot $(TOUCH_ALL)/socialtouch --out docs/figures --kind pareto --name touch-all-socialtouch \
	    --format png --format svg --reference "target=75"
	$(TB) plot $(TOUCH_ALL) --out docs/figures/touch-all --kind cd --format png --format svg

clean:
	rm -rf $(VENV) build *.egg-info

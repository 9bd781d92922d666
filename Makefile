# touchbench: the two commands of the README, and the paper reproduction.
#   make demo              set up .venv and run the main job
#   make test              set up .venv (with the dev, deep, dist and peers extras and the example plugin)
#                          and run the tests
#   make snapshots         record the names every registry holds (tests/snapshots/), after adding an entry
#   make reproduce-papers  run touchbench/protocols/papers/ and write results/papers/REPORT.md
#   make examples          run the example protocols on real HAART and regenerate the example
#                          leaderboards and report (results/examples/, results/touch-haart/) and
#                          the figures the README shows (docs/figures/, stable names)
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
EXTRAS ?= dev,deep,dist,peers
PROFILE ?= quick
JOBS ?= 2
RUNS ?= results/runs
TB := $(BIN)/touchbench

.PHONY: setup demo test snapshots reproduce-papers examples clean

PLUGIN := examples/touchbench-plugin-example

# The example plugin is installed as users install one (not editable): the tests run it by name.
$(VENV)/.installed-$(subst ,,$(EXTRAS)): pyproject.toml $(PLUGIN)/pyproject.toml $(wildcard $(PLUGIN)/src/*/*.py)
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[$(EXTRAS)]"
	$(BIN)/python -m pip install -q ./$(PLUGIN)
	touch $@

setup: $(VENV)/.installed-$(subst ,,$(EXTRAS))

demo: setup
	$(BIN)/touchbench demo

test: setup
	$(BIN)/python -m pytest -q -p no:cacheprovider

snapshots: setup
	$(BIN)/python tests/snapshots/registries.py

reproduce-papers: setup
	$(BIN)/touchbench papers reproduce --profile $(PROFILE)

examples: setup
	$(TB) run example-haart-loso --out $(RUNS)/example-haart-loso --jobs $(JOBS) --no-progress
	$(TB) run example-haart-early --out $(RUNS)/example-haart-early --jobs $(JOBS) --no-progress
	$(TB) run touch-haart-loso --out $(RUNS)/touch-haart-loso --jobs $(JOBS) --no-progress
	$(TB) run touch-haart-challenge --out $(RUNS)/touch-haart-challenge --jobs $(JOBS) --no-progress
	$(TB) leaderboard $(RUNS)/example-haart-loso $(RUNS)/example-haart-early --out results/examples \
	    --format md --format csv --format json
	$(TB) report $(RUNS)/example-haart-loso $(RUNS)/example-haart-early --out results/examples \
	    --title "touchbench example: real HAART, leave-one-subject-out"
	$(TB) leaderboard $(RUNS)/touch-haart-loso $(RUNS)/touch-haart-challenge --out results/touch-haart \
	    --format md --format csv
	$(TB) plot $(RUNS)/example-haart-loso --out docs/figures --name example-haart-loso --format png --format svg \
	    --kind pareto --kind confusion --kind cd --reference "Gaus 2015 challenge=66.5"
	$(TB) plot $(RUNS)/touch-haart-loso --out docs/figures --kind pareto --name touch-haart-loso --format png --format svg \
	    --reference "Al-mashhadani 2021 CNN=83.2"
	$(TB) plot $(RUNS)/touch-haart-challenge --out docs/figures --kind pareto --name touch-haart-challenge --format png --format svg \
	    --reference "best 2015 entry=70.9" --reference "Gaus 2015=66.5" --reference "2023 transformer*=72.8"

clean:
	rm -rf $(VENV) build *.egg-info

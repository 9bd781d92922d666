# touchbench: the two commands of the README, and the paper reproduction.
#   make demo              set up .venv and run the main job
#   make test              set up .venv (with the dev, deep, dist and peers extras) and run the tests
#   make reproduce-papers  run touchbench/protocols/papers/ and write results/papers/REPORT.md
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
EXTRAS ?= dev,deep,dist,peers
PROFILE ?= quick

.PHONY: setup demo test reproduce-papers bench clean

$(VENV)/.installed-$(subst ,,$(EXTRAS)): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[$(EXTRAS)]"
	touch $@

setup: $(VENV)/.installed-$(subst ,,$(EXTRAS))

demo: setup
	$(BIN)/touchbench demo

test: setup
	$(BIN)/python -m pytest -q -p no:cacheprovider

reproduce-papers: setup
	$(BIN)/touchbench papers reproduce --profile $(PROFILE)

clean:
	rm -rf $(VENV) build *.egg-info

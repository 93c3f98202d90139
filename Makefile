# Two commands for a newcomer:  `make demo` (set up, build, run the main scenario)
# and `make test` (the test suite, as CI runs it).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup fmus demo test lint bench fuzz docs clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[dev,docs]"
	touch $(STAMP)

setup: $(STAMP)

fmus: $(STAMP)
	$(BIN)/quadcosim build

demo: fmus
	$(BIN)/quadcosim run tp --out results/tp --overwrite
	@echo "quadcosim is installed in $(VENV): activate it with  . $(VENV)/bin/activate  (or call $(BIN)/quadcosim)"

test: fmus
	$(BIN)/ruff check .
	$(MAKE) docs
	$(BIN)/python -m pytest -q

# The documentation site, warnings as errors; its lab figures are made by the commands it shows.
docs: fmus
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs docs/_build/html

lint: $(STAMP)
	$(BIN)/ruff check .

bench: fmus
	$(BIN)/quadcosim bench

fuzz: fmus
	$(BIN)/python -m benchmarks.fuzz

clean:
	rm -rf build results docs/_build docs/_generated

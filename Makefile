# Two commands for a newcomer:  `make demo` (set up, build, run the main scenario)
# and `make test` (the test suite, as CI runs it).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup fmus demo test lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[dev]"
	touch $(STAMP)

setup: $(STAMP)

fmus: $(STAMP)
	$(BIN)/quadcosim build

demo: fmus
	$(BIN)/quadcosim run tp --out results/tp --overwrite
	@echo "quadcosim is installed in $(VENV): activate it with  . $(VENV)/bin/activate  (or call $(BIN)/quadcosim)"

test: fmus
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check .

bench: fmus
	$(BIN)/quadcosim bench

clean:
	rm -rf build results

# Two commands for a newcomer:  `make demo` (set up, build, run the main scenario)
# and `make test` (the test suite, as CI runs it).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# setuptools' BuildBackendWarning on every editable install is information (README), not a fault
QUIET_EDITABLE := PYTHONWARNINGS="ignore:Editable installation"

.PHONY: setup windows-tools fmus demo lab test kernels digests references lint bench fuzz docs clean

$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 12))' || { echo "quadcosim needs Python 3.12 or newer; $(PYTHON) is $$($(PYTHON) -V 2>&1). Install 3.12 (pyenv install 3.12, uv python install 3.12, or conda create -n quadcosim python=3.12) and run make PYTHON=python3.12" >&2; exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(QUIET_EDITABLE) $(BIN)/pip install --quiet -e ".[dev,docs]"
	touch $(STAMP)

setup: $(STAMP)

# The Windows binaries of the FMUs (mingw-w64) and the test that runs them (Wine), on Debian or
# Ubuntu: installed when missing and the user may (root), else said how; CI calls it before
# `make test`. Without them the FMUs are built for Linux alone and that test is skipped.
WINDOWS_PACKAGES := gcc-mingw-w64-x86-64 wine wine64
windows-tools:
	@if command -v x86_64-w64-mingw32-gcc >/dev/null && command -v wine >/dev/null; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
		echo "installing $(WINDOWS_PACKAGES)"; \
		apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
			$(WINDOWS_PACKAGES) >/dev/null; \
	else echo "no mingw-w64 or Wine: the FMUs get no Windows binaries (install: sudo apt-get install $(WINDOWS_PACKAGES))"; fi

fmus: $(STAMP)
	$(BIN)/quadcosim build

demo: fmus
	$(BIN)/quadcosim run tp --out results/tp --overwrite
	@echo "quadcosim is installed in $(VENV): activate it with  . $(VENV)/bin/activate  (or call $(BIN)/quadcosim)"

# JupyterLab on the notebooks (the `notebooks` extra, installed on first use); jupytext opens
# the .py files as notebooks. LAB_ARGS passes options to it; as root (a container) it starts
# with --allow-root --no-browser, which JupyterLab otherwise refuses to start without
# (reach it from outside with LAB_ARGS="--allow-root --no-browser --ip=0.0.0.0").
LAB_ARGS ?= $(if $(filter 0,$(shell id -u)),--allow-root --no-browser,)
lab: fmus
	$(BIN)/python -c 'import jupyterlab' 2>/dev/null || $(QUIET_EDITABLE) $(BIN)/pip install --quiet -e ".[notebooks]"
	$(BIN)/jupyter lab $(LAB_ARGS) notebooks

# The suite on both cores (pytest-xdist): the FMU pool, the numba cache and every test's files are
# per worker process or per test.
test: fmus
	$(BIN)/ruff check .
	$(MAKE) docs
	$(BIN)/python -m pytest -q -n 2

# The trajectory references and the findings' quick check under kernels other than this CPU's
# own (OpenBLAS's oldest, numba's generic target, numpy's SIMD dispatch off, libm without FMA):
# a test that holds on one machine only fails here.
kernels: fmus
	OPENBLAS_CORETYPE=Prescott NUMBA_CPU_NAME=generic $(BIN)/python -m pytest -q -p no:cacheprovider $(KERNEL_TESTS)
	NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4 AVX512_ICL AVX512_SPR" GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-AVX,-FMA4 \
		$(BIN)/python -m pytest -q -p no:cacheprovider $(KERNEL_TESTS)
KERNEL_TESTS := tests/test_trajectories_unchanged.py tests/test_portable.py tests/test_chunks.py

# Bit-exact digests of the reference runs on this machine: saved by the first call, compared by
# the next (before and after a refactor that must not change one bit).
digests: fmus
	$(BIN)/python tests/trajectory_runs.py digests

# Re-measure the spread across kernels and rewrite the trajectory references (after a deliberate
# change of physics or numerics).
references: fmus
	$(BIN)/python tests/trajectory_runs.py references

# The documentation site, warnings as errors; its lab figures are made by the commands it shows.
docs: fmus
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs docs/_build/html

lint: $(STAMP)
	$(BIN)/ruff check .

bench: fmus
	$(BIN)/quadcosim bench

fuzz: fmus
	$(BIN)/python -m quadcosim.benchmarks.fuzz

clean:
	rm -rf build results docs/_build docs/_generated

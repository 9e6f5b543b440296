# Two commands do all set-up on a fresh machine with Python >= 3.11 and pip:
#   make run    install into .venv and run the default scene end to end
#   make test   install into .venv (with test extras), lint, and run the test suite
# Also: make test-fast (the inner loop: no slow tests), make lint (ruff + snakefmt, no writes).
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV ?= .venv
BIN := $(VENV)/bin
JOBS ?= 2
SCENE ?=

.PHONY: install install-test run test test-fast lint browser dryrun report bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# `make run` installs what running needs (the library and its `pipeline` extra); the test extras (Tamaas,
# ContactMechanics, hypothesis, linters: several hundred MB) come only with `make test`. constraints.txt
# pins the versions the test suite last passed with: `pip install -c constraints.txt -e '.[test]'` for that
# environment.
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	@echo "Installing roughcontact and its pipeline extra into $(VENV) (numpy, scipy, pyFFTW, xarray, netCDF4,"
	@echo "matplotlib, Snakemake, SurfaceTopography): about 1-2 minutes on a fresh machine, once."
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[pipeline]'
	touch $@

$(VENV)/.installed-test: pyproject.toml $(VENV)/.installed
	@echo "Installing the test extras into $(VENV) (Tamaas, ContactMechanics, MPI, Playwright, linters):"
	@echo "about 1 minute more, once."
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@

install: $(VENV)/.installed

install-test: $(VENV)/.installed-test

run: install
	$(BIN)/snakemake -j$(JOBS) $(if $(SCENE),--config scene=$(SCENE))

dryrun: install
	$(BIN)/snakemake -n $(if $(SCENE),--config scene=$(SCENE))

# Lint runs first (seconds) and stops `make test` when it fails. One pytest worker per core
# (pytest-xdist): most tests use one core, so a serial run left the second idle (28 min serial
# on 2 quiet cores on 2026-11-26, over the 30-min CI budget under load). `--dist loadgroup` keeps
# the tests of the demo run on one worker (tests/conftest.py), so the demo runs once, not per worker
# (pytest < 9.2: tests/test_xdist_groups.py); `--durations=30` prints the slowest tests, to keep CI
# under its 30 min (2026-11-28, a fresh clone beside two niced N = 4096 solves: 25 min in all).
test: install-test lint browser
	PATH=$(abspath $(BIN)):$$PATH $(BIN)/python -m pytest -n $(JOBS) --dist loadgroup --durations=30

# tests/test_reader.py opens every scene's report in a real browser: Playwright (the test extra) drives Debian's
# chromium, installed here when missing and possible (root and apt-get); Playwright's own browser download is
# not used. Never fails: without chromium that test skips, saying why.
browser:
	@if command -v chromium >/dev/null 2>&1; then \
		echo "chromium: $$(command -v chromium)"; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		echo "installing chromium (apt-get) for the report's browser test"; \
		{ apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium; } >/dev/null 2>&1 \
			|| echo "could not install chromium: the report's browser test will skip"; \
	else \
		echo "no chromium, and installing it needs root and apt-get: the report's browser test will skip"; \
	fi

# The inner loop (under 3 min on 2 cores: 2 min 22 s on 2026-12-03, one pytest worker per core):
# every test not marked slow. Slow tests (real runs of small scenes, dry runs of the scenes' DAGs,
# MPI runs, concurrency and bootstrap studies, and every test that took over 3 s in test-fast's own
# run, `--durations=0`, 2026-12-03: 8 min 41 s before they were marked) run in `make test`.
test-fast: install-test
	PATH=$(abspath $(BIN)):$$PATH $(BIN)/python -m pytest -m "not slow" -n $(JOBS) --dist loadgroup

# Checks only, never rewrites: ruff over the Python, snakefmt over the rules (settings in
# pyproject.toml). Both always run; it fails if either finds something.
RUFF_PATHS := src tests benchmarks workflow/scripts
SNAKEFMT_PATHS := Snakefile workflow/rules
lint: install-test
	@status=0; \
	echo "$(BIN)/ruff check $(RUFF_PATHS)"; \
	$(BIN)/ruff check $(RUFF_PATHS) || status=1; \
	echo "$(BIN)/snakefmt --check $(SNAKEFMT_PATHS)"; \
	$(BIN)/snakefmt --check $(SNAKEFMT_PATHS) || { $(BIN)/snakefmt --compact-diff $(SNAKEFMT_PATHS); status=1; }; \
	exit $$status

report: install
	$(BIN)/snakemake --report report.html $(if $(SCENE),--config scene=$(SCENE))

bench: install-test
	$(BIN)/python benchmarks/bench_solver.py

clean:
	rm -rf results/*/ .snakemake report.html

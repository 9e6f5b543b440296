# Two commands do all set-up on a fresh machine with Python >= 3.11 and pip:
#   make run    install into .venv and run the default scene end to end
#   make test   install into .venv (with test extras) and run the test suite
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV ?= .venv
BIN := $(VENV)/bin
JOBS ?= 2
SCENE ?=

.PHONY: install run test dryrun report bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@

install: $(VENV)/.installed

run: install
	$(BIN)/snakemake --workflow-profile workflow/profiles/default -j$(JOBS) $(if $(SCENE),--config scene=$(SCENE))

dryrun: install
	$(BIN)/snakemake -n $(if $(SCENE),--config scene=$(SCENE))

test: install
	PATH=$(abspath $(BIN)):$$PATH $(BIN)/python -m pytest

report: install
	$(BIN)/snakemake --report report.html $(if $(SCENE),--config scene=$(SCENE))

bench: install
	$(BIN)/python benchmarks/bench_solver.py

clean:
	rm -rf results/*/ .snakemake report.html

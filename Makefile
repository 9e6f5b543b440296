# Two commands do all set-up on a fresh machine with Python >= 3.11 and pip:
#   make run    install into .venv and run the default scene end to end
#   make test   install into .venv (with test extras), lint, and run the test suite
# Also: make test-fast (the inner loop: no slow tests), make lint (ruff + snakefmt, no writes).
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV ?= .venv
BIN := $(VENV)/bin
JOBS ?= 2
SCENE ?=

.PHONY: install run test test-fast lint dryrun report bench clean

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

# Lint runs first (seconds) and stops `make test` when it fails.
test: install lint
	PATH=$(abspath $(BIN)):$$PATH $(BIN)/python -m pytest

# The inner loop (under 3 min on 2 cores): no test marked slow, and none of these (`make test`
# runs them): real runs of small scenes, the paper scene's 2100-job DAG, many dry runs in one test,
# machine-loading and long statistical tests - each 15 s to 2 min on 2 cores.
FAST_DESELECT := \
	tests/test_workflow.py::test_tiny_real_run \
	tests/test_workflow.py::test_unconverged_steps_are_flagged_counted_and_excluded \
	tests/test_workflow.py::test_a_file_made_for_another_case_or_scene_is_refused \
	tests/test_workflow.py::test_mistyped_target_fails_at_once \
	'tests/test_workflow.py::test_dry_run_every_shipped_scene[paper]' \
	tests/test_accuracy.py::test_tiny_accuracy_scene_end_to_end \
	tests/test_effects.py::test_optional_outputs_and_effects_add_exactly_their_variables \
	tests/test_determinism.py::test_fft_results_identical_across_concurrent_processes \
	tests/test_fit.py::test_recovers_known_constants_from_noisy_synthetic_data \
	tests/test_fit.py::test_bootstrap_error_shrinks_with_more_seeds
test-fast: install
	PATH=$(abspath $(BIN)):$$PATH $(BIN)/python -m pytest -m "not slow" $(addprefix --deselect ,$(FAST_DESELECT))

# Checks only, never rewrites: ruff over the Python, snakefmt over the rules (settings in
# pyproject.toml). Both always run; it fails if either finds something.
RUFF_PATHS := src tests benchmarks workflow/scripts
SNAKEFMT_PATHS := Snakefile workflow/rules
lint: install
	@status=0; \
	echo "$(BIN)/ruff check $(RUFF_PATHS)"; \
	$(BIN)/ruff check $(RUFF_PATHS) || status=1; \
	echo "$(BIN)/snakefmt --check $(SNAKEFMT_PATHS)"; \
	$(BIN)/snakefmt --check $(SNAKEFMT_PATHS) || { $(BIN)/snakefmt --compact-diff $(SNAKEFMT_PATHS); status=1; }; \
	exit $$status

report: install
	$(BIN)/snakemake --report report.html $(if $(SCENE),--config scene=$(SCENE))

bench: install
	$(BIN)/python benchmarks/bench_solver.py

clean:
	rm -rf results/*/ .snakemake report.html

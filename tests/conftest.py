"""Shared fixtures: paths of the repository, a runner for the snakemake CLI, solver options for one test."""
import contextlib
import copy
import importlib.util
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from roughcontact.solver import set_options

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).parent / "snakemake")


def load_script(path: Path, name: str):
    """A script that is not part of the package (``benchmarks/...``) imported as module ``name``."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ROUGHCONTACT_ARRAY_BACKEND=cupy runs every solve that names no backend on the GPU (the hard-case
# suite on a lent GPU, benchmarks/gpu/run.sh): the solver's explicit process-wide option
# (roughcontact.solver.set_options). CI leaves it unset: numpy.
if os.environ.get("ROUGHCONTACT_ARRAY_BACKEND"):
    set_options(array_backend=os.environ["ROUGHCONTACT_ARRAY_BACKEND"])


@pytest.fixture
def solver_options():
    """``solver_options(method=..., array_backend=...)`` sets solver options for this test only
    (:func:`roughcontact.solver.set_options`, restored after it)."""
    with contextlib.ExitStack() as stack:
        yield lambda **options: stack.enter_context(set_options(**options))


@pytest.fixture(scope="session")
def repo():
    return REPO


@pytest.fixture(scope="session")
def shipped_config():
    with open(REPO / "config" / "config.yaml") as fh:
        return yaml.safe_load(fh)


# Caps on wall-clock time only catch a hang: ~20x the slowest normal run (the demo scene,
# 35 s on 2 quiet cores, 1.5 min on busy ones). ROUGHCONTACT_TEST_TIME_SCALE multiplies every
# cap given to run_snakemake (e.g. 3 on a heavily shared machine).
SNAKEMAKE_TIMEOUT_S = 1800
TIME_SCALE = float(os.environ.get("ROUGHCONTACT_TEST_TIME_SCALE", "1"))


def run_snakemake(workdir, *args, timeout=SNAKEMAKE_TIMEOUT_S, env=None):
    """Run snakemake in ``workdir`` (a copy of the workflow); returns CompletedProcess.

    Past ``timeout`` seconds (times ROUGHCONTACT_TEST_TIME_SCALE) Snakemake and its jobs (its own
    process group) are killed and the test fails saying so, with the end of their output.
    """
    limit = timeout * TIME_SCALE
    proc = subprocess.Popen([SNAKEMAKE, *args], cwd=workdir, env=env, text=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True)
    try:
        stdout, stderr = proc.communicate(timeout=limit)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        stdout, stderr = proc.communicate()
        pytest.fail(f"snakemake {' '.join(args)} did not finish within {limit:.0f} s (killed); last output:\n"
                    f"{stdout[-2000:]}\n{stderr[-4000:]}")
    except BaseException:  # e.g. Ctrl-C: its own session would outlive pytest
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise
    return subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)


def copy_workflow(dest: Path, config: dict | None = None) -> Path:
    """Copy Snakefile, workflow/, profiles/, config/, envs/ and data/ into ``dest``; optionally replace the config.

    ``profiles/default`` comes along: Snakemake reads it in every run from the copy, as it does in the
    repository (the default workflow profile), so the tests run what a user's ``snakemake`` runs.
    """
    dest.mkdir(parents=True, exist_ok=True)
    shutil.copy(REPO / "Snakefile", dest / "Snakefile")
    shutil.copytree(REPO / "workflow", dest / "workflow", dirs_exist_ok=True)
    shutil.copytree(REPO / "profiles", dest / "profiles", dirs_exist_ok=True)
    shutil.copytree(REPO / "data", dest / "data", dirs_exist_ok=True)
    shutil.copytree(REPO / "config", dest / "config", dirs_exist_ok=True)
    shutil.copytree(REPO / "envs", dest / "envs", dirs_exist_ok=True)
    if config is not None:
        with open(dest / "config" / "config.yaml", "w") as fh:
            yaml.safe_dump(config, fh, sort_keys=False)
    return dest


def edited_contact(cfg: dict, scene: str = "tiny", **edits) -> dict:
    """A deep copy of ``cfg`` with ``edits`` applied to scene ``scene``'s contact block: dotted keys
    (``"solver.batch"``), each set to its value, or removed where the value is None."""
    cfg = copy.deepcopy(cfg)
    block = cfg["scenes"][scene]["contact"]
    for dotted, value in edits.items():
        *head, last = dotted.split(".")
        node = block
        for key in head:
            node = node.setdefault(key, {})
        if value is None:
            node.pop(last)
        else:
            node[last] = value
    return cfg


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Every test that uses :func:`demo_run` in one xdist group (``make test`` runs ``--dist loadgroup``).

    First among the hooks (``tryfirst``): pytest-xdist's worker reads the groups in its own hook of
    the same name; a mark added after it is ignored (and the demo ran once per worker).

    A session fixture runs once per worker: spread over two workers, the demo ran twice, each a
    ``-j2`` Snakemake run on a 2-core machine (~1.5 min quiet, several under load). In one group the
    tests share one run, one after the other, while the other worker takes the rest of the suite.
    """
    for item in items:
        if "demo_run" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.xdist_group("demo_run"))


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory):
    """A workflow copy where the shipped default scene (demo) has run, as `make run` runs it.

    Run once per session (about 1.5 min on 2 cores) and shared by the tests that need its results
    (test_workflow's byte-identical rerun, test_report's browser check of the report).
    """
    wd = copy_workflow(tmp_path_factory.mktemp("demo") / "wf")
    res = run_snakemake(wd, "-j2")
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    return wd

"""Shared fixtures: paths of the repository, a runner for the snakemake CLI, solver options for one test."""
import contextlib
import copy
import importlib.util
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
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


def copy_workflow(dest: Path, config: dict | None = None, source: Path = REPO) -> Path:
    """Copy Snakefile, workflow/, profiles/, config/, envs/ and data/ of ``source`` (this repository) into ``dest``;
    optionally replace the config.

    ``profiles/default`` comes along: Snakemake reads it in every run from the copy, as it does in the
    repository (the default workflow profile), so the tests run what a user's ``snakemake`` runs.
    """
    dest.mkdir(parents=True, exist_ok=True)
    shutil.copy(source / "Snakefile", dest / "Snakefile")
    for name in ("workflow", "profiles", "data", "config", "envs"):
        shutil.copytree(source / name, dest / name, dirs_exist_ok=True)
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


#: A scene run shared by the tests (a session fixture): its working copy, the scene it ran, and that scene's results.
@dataclass(frozen=True)
class SceneRun:
    wd: Path
    scene: str

    @property
    def out(self) -> Path:
        return self.wd / "results" / self.scene


def _merged(base: dict, edits: dict) -> dict:
    """``edits`` over ``base`` as a scene merges over ``defaults``: mappings key by key, anything else replaced."""
    out = copy.deepcopy(base)
    for key, value in edits.items():
        out[key] = _merged(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) \
            else copy.deepcopy(value)
    return out


def _shipped_config() -> dict:
    with open(REPO / "config" / "config.yaml") as fh:
        return yaml.safe_load(fh)


def shipped_scene_config(scene: str, edits: dict | None) -> dict:
    """The shipped config running ``scene``, its block with ``edits`` merged over it (None: as shipped)."""
    cfg = _shipped_config()
    cfg["scene"] = scene
    if edits is not None:
        cfg["scenes"][scene] = _merged(cfg["scenes"][scene] or {}, edits)
    return cfg


#: The tests' tiny scene: a generated 2-D study with representativity, contact and fit at N = 32 (seconds).
TINY = {
    "scene": "tiny",
    "scenes": {
        "tiny": {
            "description": "tiny end-to-end run for the tests",
            "representativity": {
                "surface": {"N": 32, "rms_height": 0.1},
                "grid": {"k_l": ["1", "4"], "k_s": ["8"], "H": ["0.8"]},
                "seeds": 2,
                "n_bins": 20,
                "examples": [{"k_l": "1", "k_s": "8"}, {"k_l": "4", "k_s": "8"}],
            },
            "contact": {
                "surface": {"N": 32, "rms_slope": 0.1},
                "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5", "0.8"]},
                "seeds": 2,
                "load": {"p_max": 0.01, "n_steps": 12},
                "solver": {"tol": 1e-8},
            },
            "fit": {"window": [0.01, 0.3], "n_boot": 20},
        },
        "reponly": {
            "representativity": {
                "surface": {"N": 32, "rms_height": 0.1},
                "grid": {"k_l": ["1"], "k_s": ["8"], "H": ["0.8"]},
                "seeds": 2,
            }
        },
    },
}

LINESCANS = REPO / "tests" / "data" / "linescans"

#: The adhesion law of the shipped `adhesion` scene and of the tests' adhesive scenes.
ADHESION = {"adhesion": {"law": "exponential", "work": 1e-5, "range": 1e-3}}


@dataclass(frozen=True)
class Family:
    """A family of shipped scenes (they differ only in grid, seeds, resolution or loads) and its tiny variant.

    ``config()`` is the config the variant runs (None: the shipped config as it is) and ``scene`` the scene it runs;
    ``files`` are copied into the working copy first (``{destination: source}``). Every family runs once per test
    session, by its fixture (``fixture``), which the conftest hook puts in an xdist group of its own.
    """

    name: str
    scene: str
    fixture: str
    config: Callable[[], dict | None]
    files: Mapping[str, Path] = field(default_factory=dict)
    #: a scene run as shipped (the report's screenshots name it so); else a tiny variant of one
    shipped: bool = False


def _tiny_lines() -> dict:
    """The `lines` scene smaller: contact on profiles of N = 1024 at its resolution (32 points per lambda_s) and its
    bandwidth (k_s / k_l = 32), 2 H, 2 seeds, its loads and fields; the representativity map over 2 k_l x 2 k_s at
    N = 256."""
    return shipped_scene_config("lines", {
        "description": "The lines scene small (the tests' variant): profiles of N=1024 points, 1 k_l x 2 H x 2 seeds.",
        "representativity": {"surface": {"N": 256}, "grid": {"k_l": ["2", "4"], "k_s": ["8", "16"]}, "seeds": 2},
        "contact": {"surface": {"N": 1024}, "grid": {"k_l": ["1"], "k_s": ["32"]}, "seeds": 2},
        "fit": {"n_boot": 20},
    })


def _line_scans() -> dict:
    """Two real line scans of SurfaceTopography's test suite (134 and 132 points, non-uniform), the default loads."""
    return {"scene": "linescans", "scenes": {"linescans": {
        "description": "Two real line scans (SurfaceTopography's nonuniform.asc and xy-1.txt) through every stage.",
        "topography": {"files": {"scan": "nonuniform.asc", "xy": "xy-1.txt"}, "unit": "um", "file_unit": "um",
                       "detrend": "height"},
        "contact": {"load": {"n_steps": 30}},
        "fit": {"n_boot": 20},
    }}}


def _tiny_adhesion() -> dict:
    """The `adhesion` scene at N = 32 (k_l = 2, k_s = 8), 2 H, 2 seeds, 4 load steps."""
    return shipped_scene_config("adhesion", {
        "description": "The adhesion scene small (the tests' variant): N=32, 2 H, 2 seeds, 4 load steps.",
        "contact": {"surface": {"N": 32}, "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5", "0.8"]},
                    "load": {"p_max": 0.005, "n_steps": 4}, "effects": copy.deepcopy(ADHESION)},
    })


def _tiny_array() -> dict:
    """The `array` scene's two files with 8 load steps and 20 histogram bins."""
    return shipped_scene_config("array", {
        "description": "The array scene with 8 load steps (the tests' variant): two .npy height maps.",
        "representativity": {"n_bins": 20},
        "contact": {"load": {"n_steps": 8}},
        "fit": {"window": [0.01, 0.3], "n_boot": 20},
    })


def _tiny_full_contact() -> dict:
    """The `full-contact` scene at N = 64: 2 H, 2 seeds, 10 geometric steps to past full contact, every output."""
    return shipped_scene_config("full-contact", {
        "description": "The full-contact scene small (the tests' variant): N=64, 2 H, 2 seeds, 10 steps.",
        "contact": {"surface": {"N": 64}, "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.36", "0.84"]}, "seeds": 2,
                    "load": {"n_steps": 10}},
        "fit": {"n_boot": 20},
    })


#: The accuracy study on N = 16 to 64 (test_accuracy checks what it computes).
ACCURACY = {
    "scene": "acc",
    "scenes": {
        "acc": {
            "accuracy": {
                "surface": {"L": 1.0, "rms_slope": 0.1},
                "k_l": "2", "k_s": "8", "H": ["0.5", "0.8"],
                "p_max": 0.02,
                "reference": {"N": "64", "tol": "1e-10", "n_steps": "20"},
                "defaults": {"N": "32", "tol": "1e-8", "n_steps": "20"},
                "axes": {"N": ["16", "32"], "tol": ["1e-4"], "n_steps": ["10"]},
                "seeds": 1,
                "seed_axis": ["1", "3"],
                "kappa_at": 0.15,
            }
        }
    },
}

#: The kappa-gap study on N = 32 to 128 (test_kappa_gap checks what it computes).
KAPPA_GAP = {
    "scene": "kg",
    "scenes": {"kg": {"kappa_gap": {
        "surface": {"L": 1.0, "rms_slope": 0.1},
        "k_l": "2", "k_s": "8", "H": ["0.5", "0.8"],
        "variants": {
            "baseline": {"role": "baseline", "N": "64", "seeds": 2, "p_max": 0.004},
            "load": {"role": "load", "N": "64", "seeds": 2, "p_max": 0.03},
            "N32": {"role": "resolution", "N": "32", "seeds": 2, "p_max": 0.004, "n_steps": 8,
                    "schedule": "geometric"},
            "N64": {"role": "resolution", "N": "64", "seeds": 2, "p_max": 0.004, "n_steps": 8,
                    "schedule": "geometric"},
            "N128": {"role": "resolution", "N": "128", "seeds": 1, "p_max": 0.004, "n_steps": 8,
                     "schedule": "geometric"},
            "ref": {"role": "solver", "N": "32", "seeds": 1, "p_max": 0.004},
            "sk": {"role": "solver", "N": "32", "seeds": 1, "p_max": 0.004, "method": "stanley-kato",
                   "tol": "1e-3"},
        },
    }}},
}

#: Every family of scenes the reader's test (tests/test_reader.py) opens, in the order a shipped scene is matched to
#: one (tests/test_reader.py: the first whose variant computes all the scene computes). `line-scans` is no shipped
#: scene: real line scans, which the issue-60 acceptance names.
FAMILIES = {f.name: f for f in (
    Family("paper-like", "demo", "demo_run", lambda: None, shipped=True),
    Family("profiles", "lines", "lines_run", _tiny_lines),
    Family("line-scans", "linescans", "line_scans_run", _line_scans,
           files={name: LINESCANS / name for name in ("nonuniform.asc", "xy-1.txt")}),
    Family("adhesion", "adhesion", "adhesion_run", _tiny_adhesion),
    Family("measured", "measured", "measured_run", lambda: shipped_scene_config("measured", None), shipped=True),
    Family("array", "array", "array_run", _tiny_array),
    Family("full-contact", "full-contact", "full_contact_run", _tiny_full_contact),
    Family("accuracy", "acc", "accuracy_run", lambda: copy.deepcopy(ACCURACY)),
    Family("kappa-gap", "kg", "kappa_gap_run", lambda: copy.deepcopy(KAPPA_GAP)),
)}

#: The session fixtures that run a scene: each in an xdist group of its own (pytest_collection_modifyitems).
RUN_FIXTURES = tuple(f.fixture for f in FAMILIES.values())

#: The indirect parameter of a test over the families (tests/test_reader.py): its tests go to their family's group.
FAMILY_PARAMETER = "family_run"


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Every test that uses a scene run (:data:`RUN_FIXTURES`, e.g. :func:`demo_run`) in that run's xdist group
    (``make test`` runs ``--dist loadgroup``); a test over the families (parameter :data:`FAMILY_PARAMETER`) in its
    family's.

    First among the hooks (``tryfirst``): pytest-xdist's worker reads the groups in its own hook of
    the same name; a mark added after it is ignored (and the demo ran once per worker).

    A session fixture runs once per worker: spread over two workers, the demo ran twice, each a
    ``-j2`` Snakemake run on a 2-core machine (~1.5 min quiet, several under load). In one group the
    tests share one run, one after the other, while the other worker takes the rest of the suite.
    """
    for item in items:
        names = getattr(item, "fixturenames", ())
        used = [name for name in RUN_FIXTURES if name in names]
        callspec = getattr(item, "callspec", None)
        if FAMILY_PARAMETER in names and callspec is not None and callspec.params.get(FAMILY_PARAMETER) in FAMILIES:
            used = [FAMILIES[callspec.params[FAMILY_PARAMETER]].fixture]
        if used:
            item.add_marker(pytest.mark.xdist_group(used[0]))


def run_family(tmp_path_factory, name: str) -> SceneRun:
    """Family ``name``'s scene run in a fresh workflow copy (``snakemake -j2``), its wall time printed."""
    family = FAMILIES[name]
    wd = copy_workflow(tmp_path_factory.mktemp(name) / "wf", family.config())
    for dest, source in family.files.items():
        shutil.copy(source, wd / dest)
    start = time.monotonic()
    res = run_snakemake(wd, "-j2", "--config", f"scene={family.scene}")
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    print(f"scene run {name} ({family.scene}): {time.monotonic() - start:.0f} s")
    return SceneRun(wd, family.scene)


@pytest.fixture(scope="session")
def lines_run(tmp_path_factory):
    """The `lines` scene's tiny variant, run once (test_lines_scene, test_reader)."""
    return run_family(tmp_path_factory, "profiles")


@pytest.fixture(scope="session")
def line_scans_run(tmp_path_factory):
    """Two real line scans through every stage, run once (test_lines_scene, test_reader)."""
    return run_family(tmp_path_factory, "line-scans")


@pytest.fixture(scope="session")
def adhesion_run(tmp_path_factory):
    """The `adhesion` scene's tiny variant, run once (test_adhesion_scene, test_reader)."""
    return run_family(tmp_path_factory, "adhesion")


@pytest.fixture(scope="session")
def measured_run(tmp_path_factory):
    """The shipped `measured` scene, run once (test_workflow, test_reader)."""
    return run_family(tmp_path_factory, "measured")


@pytest.fixture(scope="session")
def array_run(tmp_path_factory):
    """The `array` scene with 8 load steps, run once (test_sources, test_reader)."""
    return run_family(tmp_path_factory, "array")


@pytest.fixture(scope="session")
def full_contact_run(tmp_path_factory):
    """The `full-contact` scene's tiny variant, run once (test_reader)."""
    return run_family(tmp_path_factory, "full-contact")


@pytest.fixture(scope="session")
def accuracy_run(tmp_path_factory):
    """The tiny accuracy study, run once (test_accuracy, test_reader)."""
    return run_family(tmp_path_factory, "accuracy")


@pytest.fixture(scope="session")
def kappa_gap_run(tmp_path_factory):
    """The tiny kappa-gap study, run once (test_kappa_gap, test_reader)."""
    return run_family(tmp_path_factory, "kappa-gap")


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

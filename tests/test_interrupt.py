"""Kill a run mid-way (SIGKILL Snakemake and its jobs); --rerun-incomplete completes it exactly."""
import os
import signal
import subprocess
import time

import pytest

from conftest import SNAKEMAKE, copy_workflow, run_snakemake

SCENE = {
    "scene": "kill",
    "scenes": {
        "kill": {
            "contact": {
                "surface": {"N": 128, "rms_slope": 0.1},
                "grid": {"k_l": ["4"], "k_s": ["32"], "H": ["0.5", "0.8"]},
                "seeds": 3,
                "load": {"p_max": 0.005, "n_steps": 30},
                "solver": {"tol": 1e-10},
            },
            "fit": {"window": [0.01, 0.11], "n_boot": 20},
        }
    },
}


def _outputs(root):
    return {
        p.relative_to(root): p.read_bytes()
        for p in sorted((root / "results").rglob("*"))
        if p.is_file() and p.suffix in (".nc", ".csv")
    }


@pytest.mark.slow
def test_sigkill_then_rerun_incomplete_matches_uninterrupted(tmp_path):
    ref = copy_workflow(tmp_path / "ref", SCENE)
    res = run_snakemake(ref, "-j2")
    assert res.returncode == 0, res.stderr[-3000:]

    wd = copy_workflow(tmp_path / "killed", SCENE)
    proc = subprocess.Popen([SNAKEMAKE, "-j2"], cwd=wd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    contact = wd / "results" / "kill" / "contact"
    deadline = time.time() + 120
    # Kill once the first contact case is written and others are running.
    while time.time() < deadline and not (contact.exists() and list(contact.glob("*.nc"))):
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = list(contact.glob("*.nc"))
    assert 0 < len(done) < 6, "the kill must land mid-way through the contact stage"

    # A SIGKILLed Snakemake cannot release its lock: --unlock is the documented first step.
    assert run_snakemake(wd, "--unlock").returncode == 0
    res = run_snakemake(wd, "-j2", "--rerun-incomplete")
    assert res.returncode == 0, res.stderr[-3000:]
    assert _outputs(wd) == _outputs(ref)
    assert not list((wd / "results").rglob("*.tmp")), "no temporary file may survive"

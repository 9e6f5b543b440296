"""Kill a run mid-way (SIGKILL Snakemake and its jobs); --rerun-incomplete completes it exactly."""
import os
import signal
import subprocess
import time

import pytest

from conftest import SNAKEMAKE, TIME_SCALE, copy_workflow, run_snakemake

FIRST_CASE_TIMEOUT_S = 600 * TIME_SCALE  # normally 5-30 s

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


#: What both runs make: every contact case, the aggregate and the fit (the figures and report are other tests').
TARGETS = ("results/kill/fit/cel.nc", "results/kill/fit/cel.csv")


def _outputs(root):
    return {
        p.relative_to(root): p.read_bytes()
        for p in sorted((root / "results").rglob("*"))
        if p.is_file() and p.suffix in (".nc", ".csv")
    }


@pytest.mark.slow
def test_sigkill_then_rerun_incomplete_matches_uninterrupted(tmp_path):
    ref = copy_workflow(tmp_path / "ref", SCENE)
    res = run_snakemake(ref, "-j2", *TARGETS)
    assert res.returncode == 0, res.stderr[-3000:]

    wd = copy_workflow(tmp_path / "killed", SCENE)
    log = tmp_path / "killed.log"
    with open(log, "w") as out:
        proc = subprocess.Popen([SNAKEMAKE, "-j2", *TARGETS], cwd=wd, stdout=out, stderr=subprocess.STDOUT,
                                start_new_session=True)
    contact = wd / "results" / "kill" / "contact"
    # Kill once the first contact case is written and others are running. The first one takes a
    # few seconds (two surfaces, one solve at N=128); the cap only catches a hang.
    start = time.monotonic()
    while not (contact.exists() and list(contact.glob("*.nc"))):
        waited = time.monotonic() - start
        if proc.poll() is not None or waited > FIRST_CASE_TIMEOUT_S:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            what = (f"snakemake exited with status {proc.returncode}" if waited <= FIRST_CASE_TIMEOUT_S else
                    f"no contact file within {FIRST_CASE_TIMEOUT_S} s (killed)")
            pytest.fail(f"{what} before the first contact case was written; last output:\n"
                        f"{log.read_text()[-4000:]}")
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = sorted(p.name for p in contact.glob("*.nc"))
    assert 0 < len(done) < 6, (f"the kill must land mid-way through the contact stage, but {len(done)} of 6 "
                               f"contact files were there after it ({done}); last output:\n{log.read_text()[-2000:]}")

    # A SIGKILLed Snakemake cannot release its lock: --unlock is the documented first step.
    res = run_snakemake(wd, "--unlock")
    assert res.returncode == 0, res.stderr[-3000:]
    res = run_snakemake(wd, "-j2", "--rerun-incomplete", *TARGETS)
    assert res.returncode == 0, res.stderr[-3000:]
    assert _outputs(wd) == _outputs(ref)
    assert not list((wd / "results").rglob("*.tmp")), "no temporary file may survive"

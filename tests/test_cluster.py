"""The SLURM profile on a real SLURM: tests/cluster/run_slurm_test.sh, when the machine allows.

The script brings up a single-node SLURM (Debian's slurm-wlm + munge, localhost only), runs a
small scene through workflow/profiles/slurm and requires every NetCDF/CSV output to be
byte-identical to a local -j2 run. It needs root and a package manager (or SLURM already
installed); where it cannot run it prints "SKIP: <reason>" and this test is skipped with that
reason (shown by `pytest -ra`, i.e. by `make test`).

ROUGHCONTACT_SLURM_TEST=0 skips it outright; ROUGHCONTACT_SLURM_TEST=1 requires it to run, so a
SKIP from the script fails the test instead.
"""
import os
import shutil
import signal
import subprocess
import sys

import pytest

from conftest import REPO

SCRIPT = REPO / "tests" / "cluster" / "run_slurm_test.sh"
TIMEOUT_S = 1200  # the script bounds each of its steps; this only guards against a hang


@pytest.mark.slow
def test_slurm_run_matches_local_run():
    wanted = os.environ.get("ROUGHCONTACT_SLURM_TEST", "")
    if wanted == "0":
        pytest.skip("ROUGHCONTACT_SLURM_TEST=0")
    bash = shutil.which("bash")
    if bash is None:
        pytest.skip("bash not found")
    env = {**os.environ, "PYTHON": sys.executable}
    # Own process group: on a timeout the script gets SIGTERM first, so its trap stops the daemons.
    proc = subprocess.Popen(
        [bash, str(SCRIPT)], cwd=REPO, env=env, text=True,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
    )
    try:
        stdout, stderr = proc.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            stdout, stderr = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            stdout, stderr = proc.communicate()
        pytest.fail(f"{SCRIPT.name} did not finish in {TIMEOUT_S} s:\n{(stdout + stderr)[-8000:]}")
    out = stdout + stderr
    skips = [line[len("SKIP:"):].strip() for line in stdout.splitlines() if line.startswith("SKIP:")]
    if proc.returncode == 0 and skips:
        if wanted == "1":
            pytest.fail(f"ROUGHCONTACT_SLURM_TEST=1, but {SCRIPT.name} skipped: {skips[-1]}")
        pytest.skip(f"SLURM test not run: {skips[-1]}")
    assert proc.returncode == 0, f"{SCRIPT.name} failed (status {proc.returncode}):\n{out[-8000:]}"
    assert "PASS:" in stdout and "MATCH:" in stdout, out[-5000:]

"""The SLURM profile on a real SLURM: tests/cluster/run_slurm_test.sh, when the machine allows.

The script brings up a single-node SLURM (Debian's slurm-wlm + munge, localhost only), runs a
small scene through profiles/slurm and requires every NetCDF/CSV output to be
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

from conftest import REPO, TIME_SCALE

SCRIPT = REPO / "tests" / "cluster" / "run_slurm_test.sh"
# The script caps each of its steps (node up 300 s, local run 600 s, SLURM run 1200 s; measured:
# seconds, 24 s, 77 s) and says which cap it hit; this only guards against a hang of the script
# itself, e.g. in apt-get.
TIMEOUT_S = 3600 * TIME_SCALE
SCRIPT_CAPS = {"ROUGHCONTACT_SLURM_UP_TIMEOUT": 300, "ROUGHCONTACT_SLURM_LOCAL_TIMEOUT": 600,
               "ROUGHCONTACT_SLURM_RUN_TIMEOUT": 1200}


def _failure(out: str) -> str:
    """The script's FAIL: line first (the daemon logs it prints can be long), then its output's end."""
    fails = [line for line in out.splitlines() if line.startswith("FAIL:")]
    return "\n".join(fails) + "\n--- end of the script's output:\n" + out[-8000:]


@pytest.mark.slow
def test_slurm_run_matches_local_run():
    wanted = os.environ.get("ROUGHCONTACT_SLURM_TEST", "")
    if wanted == "0":
        pytest.skip("ROUGHCONTACT_SLURM_TEST=0")
    bash = shutil.which("bash")
    if bash is None:
        pytest.skip("bash not found")
    env = {**os.environ, "PYTHON": sys.executable}
    for name, default_s in SCRIPT_CAPS.items():  # the script's own caps follow ROUGHCONTACT_TEST_TIME_SCALE
        env.setdefault(name, str(round(default_s * TIME_SCALE)))
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
            stdout, stderr = proc.communicate(timeout=120)  # its trap stops the daemons (10 s grace each)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            stdout, stderr = proc.communicate()
        last = [line for line in stdout.splitlines() if line.startswith("[slurm-test")][-1:]
        pytest.fail(f"{SCRIPT.name} did not finish within {TIMEOUT_S:.0f} s (stopped); its last step: "
                    f"{last[0] if last else 'none logged'}\n{_failure(stdout + stderr)}")
    out = stdout + stderr
    skips = [line[len("SKIP:"):].strip() for line in stdout.splitlines() if line.startswith("SKIP:")]
    if proc.returncode == 0 and skips:
        if wanted == "1":
            pytest.fail(f"ROUGHCONTACT_SLURM_TEST=1, but {SCRIPT.name} skipped: {skips[-1]}")
        pytest.skip(f"SLURM test not run: {skips[-1]}")
    assert proc.returncode == 0, f"{SCRIPT.name} failed (status {proc.returncode}):\n{_failure(out)}"
    assert "PASS:" in stdout and "MATCH:" in stdout, out[-5000:]

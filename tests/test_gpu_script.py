"""benchmarks/gpu/run.sh, the one prepared script a lent GPU runs, proven end to end on the CPU.

A device is lent for 15 minutes at a time, rarely, and a script that fails there wastes the lend. Its
``RC_SMOKE=1`` form runs every part (cold starts, the paper grid's sample, the check against single
solves, the whole grid, the host check every 8th round, tests/test_batch.py) with the numpy backend at
tiny sizes: each part must end with rc 0, and the summary must carry each part's line.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PARTS = ("cold1", "cold2", "grid", "check", "whole", "grid_k8", "tests")
#: a hang, not a slow machine: the smoke run takes ~20 s on 2 quiet cores
LIMIT_S = 300 * float(os.environ.get("ROUGHCONTACT_TEST_TIME_SCALE", "1"))

pytestmark = pytest.mark.slow


def test_the_gpu_script_runs_every_part_on_the_cpu(tmp_path):
    out = tmp_path / "out"
    env = {**os.environ, "RC_SMOKE": "1", "OUT": str(out), "PYTHON": sys.executable,
           "RC_CUPY_CACHE": str(tmp_path / "cupy-cache")}
    env.pop("ROUGHCONTACT_ARRAY_BACKEND", None)
    run = subprocess.run(["bash", "benchmarks/gpu/run.sh"], cwd=ROOT, env=env, capture_output=True, text=True,
                         timeout=LIMIT_S)
    assert run.returncode == 0, run.stderr[-2000:]
    summary = (out / "summary.txt").read_text()
    for part in PARTS:
        rows = [line for line in summary.splitlines() if line.startswith(f"| {part} |")]
        assert rows and rows[0].startswith(f"| {part} | rc 0,"), (part, rows, (out / f"{part}.log").read_text()[-2000:])
    # what each part measured reached the summary (a part can end with rc 0 and print nothing)
    assert summary.count("- cold") == 2 and "- tests: " in summary and " passed" in summary, summary
    nodes = re.search(r"max \|dA/A0\| \S+ \((\d+) nodes", summary)
    assert nodes and int(nodes.group(1)) <= 1, summary  # batched against single solves: within a node

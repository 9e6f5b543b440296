"""benchmarks/profile_iteration.py: tiny runs in their own processes (it rewraps solver classes)."""
import re
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "profile_iteration.py"


def _profile(*args) -> tuple[str, dict]:
    out = subprocess.run([sys.executable, str(SCRIPT), "--n", "64", *args], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.splitlines()
    rows = {m[1].strip(): float(m[2]) for m in (re.match(r"(.+?)\s+[\d.]+ s\s+([\d.]+) %", x) for x in lines[1:]) if m}
    assert all(0.0 <= share <= 100.0 for share in rows.values()), rows
    return lines[0], rows


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_a_tiny_profile_names_every_part_with_its_share():
    head, rows = _profile()
    assert re.match(r"N = 64, single solve: solve CPU [\d.]+ s, \d+ iterations", head), head
    want = {"measure", "join", "direction", "trial", "settle", "f32 forward", "f32 backward", "Parseval sum"}
    assert want <= set(rows), rows


@pytest.mark.parametrize("kernels", ["fused", "plain"])
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_the_batched_iteration_profiles_with_either_kernels(kernels):
    """``--batched fused|plain``: the batched iteration's kernels, transforms and start, each with its share.

    Both kernels show a round's five passes; the plain ones compose them from their kernels, which show too, where
    the fused ones make each pass one compiled call."""
    head, rows = _profile("--batched", kernels)
    assert re.match(rf"N = 64, batched iteration \({kernels} kernels\): solve CPU [\d.]+ s, \d+ iterations",
                    head), head
    want = {"forward transform", "inverse transform", "warm start", "measure", "join", "direction", "trial", "settle"}
    if kernels == "plain":
        want |= {"join_stats", "new_direction_input", "trial_stats", "shrink_stats"}
    assert want <= set(rows), rows

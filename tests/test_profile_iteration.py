"""benchmarks/profile_iteration.py: a tiny run in its own process (it rewraps solver classes)."""
import re
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "profile_iteration.py"


def test_a_tiny_profile_names_every_part_with_its_share():
    out = subprocess.run([sys.executable, str(SCRIPT), "--n", "64"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.splitlines()
    assert re.match(r"N = 64: solve CPU [\d.]+ s, \d+ iterations", lines[0]), lines[0]
    rows = {m[1].strip(): float(m[2]) for m in (re.match(r"(.+?)\s+[\d.]+ s\s+([\d.]+) %", x) for x in lines[1:]) if m}
    assert {"_direction", "_step_single", "f32 forward", "f32 backward", "Parseval sum"} <= set(rows), rows
    assert all(0.0 <= share <= 100.0 for share in rows.values()), rows

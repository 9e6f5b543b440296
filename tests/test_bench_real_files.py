"""benchmarks/bench_real_files.py: one file's line from a real solve (frt-2, 150^2, ~2 s)."""
import re
from pathlib import Path

from conftest import load_script

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_real_files.py"
DATA = Path(__file__).resolve().parent / "data" / "surfacetopography"


def _module():
    return load_script(SCRIPT, "bench_real_files")


def test_every_listed_file_is_shipped():
    assert all((DATA / name).is_file() for name, _ in _module().FILES)


def test_one_file_line_reports_a_converged_solve():
    line = _module().solve_file(DATA / "frt-2.frt", "crop")
    m = re.fullmatch(r"frt-2\.frt \(150, 150\) conv (\d+)/30 iters (\d+) paths \{.*\} cpu [\d.]+ A30 ([\d.]+)", line)
    assert m, line
    assert int(m[1]) == 30 and int(m[2]) > 30 and 0 < float(m[3]) <= 1

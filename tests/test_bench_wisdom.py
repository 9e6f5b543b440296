"""benchmarks/bench_wisdom.py: a tiny run of two wisdom files whose rows say what they measured."""
from pathlib import Path

import pytest

from conftest import load_script

bench = load_script(Path(__file__).resolve().parents[1] / "benchmarks" / "bench_wisdom.py", "bench_wisdom")


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_the_shipped_wisdom_against_itself_gives_the_same_solution(capsys):
    pytest.importorskip("pyfftw")
    from roughcontact.core import fft

    shipped = fft.WISDOM_FILE
    try:
        assert bench.main(["--new", str(shipped), "--n", "64", "--rounds", "1"]) == 0
    finally:  # the benchmark points the package at each file in turn
        bench.use(shipped)
    out = capsys.readouterr().out
    pairs = [line for line in out.splitlines() if line.startswith("| 64 | float")]
    assert len(pairs) == 4  # both precisions, in place and out of place
    solve = [line.split("|")[1:-1] for line in out.splitlines() if line.startswith("| 64 |") and "float" not in line]
    assert len(solve) == 1
    cells = [c.strip() for c in solve[0]]
    old_it, new_it = (int(x) for x in cells[4].split(", "))
    assert old_it == new_it > 0 and cells[5:] == ["True", "True"]  # same plans: same path, same areas

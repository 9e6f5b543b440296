"""benchmarks/coarse_start.py: its prolongation, and a tiny run whose rows say what they measured."""
from pathlib import Path

import numpy as np

from conftest import load_script

bench = load_script(Path(__file__).resolve().parents[1] / "benchmarks" / "coarse_start.py", "coarse_start_bench")


def test_prolong_keeps_the_coarse_nodes_and_interpolates_periodically():
    p = np.random.default_rng(0).random((4, 6))
    q = bench.prolong(p)
    assert q.shape == (8, 12)
    np.testing.assert_array_equal(q[::2, ::2], p)
    assert q[7, 0] == 0.5 * (p[3, 0] + p[0, 0])  # wraps across the cell's edge
    assert q[1, 1] == 0.25 * (p[0, 0] + p[1, 0] + p[0, 1] + p[1, 1])


def test_a_tiny_run_gives_the_same_solution_from_both_starts(capsys):
    assert bench.main(["--n", "128", "--coarsest", "32", "--rounds", "1"]) == 0
    rows = [line.split("|")[1:-1] for line in capsys.readouterr().out.splitlines()[2:]]
    assert len(rows) == 4  # two surfaces, two loads
    for row in rows:
        cells = [c.strip() for c in row]
        assert cells[-2:] == ["True", "True"], row  # same A/A0, every solve converged
        fine, coarse = (int(x) for x in cells[5].split(" + "))
        assert fine > 0 and coarse > 0  # the coarse start did solve on the coarse grids

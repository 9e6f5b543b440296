"""benchmarks/bench_solver.py: what "auto" runs at each N, the summary's columns, a tiny worker run."""

from __future__ import annotations

from pathlib import Path

import pytest

from conftest import load_script

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_solver.py"

#: The summary's columns, in order (issue 29).
SUMMARY = ["N", "steps", "iterations", "converged", "CPU [s]", "wall [s]", "ms/iter", "f32 pair [ms] (raw)",
           "pair-eq/iter", "FFT pairs/iter", "peak RSS [MB]", "Tamaas CPU [s]", "Tamaas steps",
           "CPU ratio Tamaas/ours", "max rel dA/A0"]


@pytest.fixture(scope="module")
def bench():
    return load_script(SCRIPT, "bench_solver")


def test_auto_runs_the_extras_up_to_1024_only(bench):
    small, large = bench.resolve_extras(1024, 30), bench.resolve_extras(4096, 30)
    assert small == {"plan_repeats": 2, "methods": ["pk", "pk-fourier", "pk-fourier-f32"], "tamaas_steps": 30,
                     "tracemalloc": True, "measure_pair": True}
    assert large == {"plan_repeats": 0, "methods": [], "tamaas_steps": 1, "tracemalloc": False,
                     "measure_pair": False}
    assert bench.resolve_extras(2048, 30)["tracemalloc"]
    assert bench.resolve_extras(2, 2)["tamaas_steps"] == 2  # never more steps than there are


def test_explicit_values_apply_to_every_n(bench):
    for n in (256, 4096):
        got = bench.resolve_extras(n, 30, plan_repeats=1, methods="pk", tamaas_steps=5)
        assert (got["plan_repeats"], got["methods"], got["tamaas_steps"]) == (1, ["pk"], 5)
        assert got["measure_pair"]
    assert bench.resolve_extras(512, 30, plan_repeats=0, methods="", tamaas_steps=0)["methods"] == []


def test_cupy_skips_the_host_comparisons(bench):
    got = bench.resolve_extras(512, 30, plan_repeats=2, methods="pk", tamaas_steps=30, backend="cupy")
    assert got == {"plan_repeats": 0, "methods": [], "tamaas_steps": 0, "tracemalloc": False,
                   "measure_pair": False}
    assert bench._backend_option("numpy") == {}


def test_auto_or_a_count(bench):
    assert bench._auto_int("auto") == "auto"
    assert bench._auto_int("3") == 3
    for bad in ("-1", "x"):
        with pytest.raises(Exception, match="'auto' or an integer"):
            bench._auto_int(bad)


def _result(steps=4, tamaas_steps=2):
    ours = {"wall": 2.0, "cpu": 1.6, "step_cpu_cum": [0.5, 0.9, 1.2, 1.5], "area": [0.1, 0.2, 0.3, 0.4],
            "step_time": [0.4, 0.4, 0.4, 0.4], "iterations": [10, 10, 10, 10], "converged": True,
            "time_per_iter": 0.04, "cpu_per_iter": 0.04, "wall_per_iter": 0.05, "pairs_double": 8,
            "pairs_single": 100, "fft_pairs_per_iter": 2.7}
    tamaas = {"wall": 9.0, "cpu": 9.0, "area": [0.1, 0.25][:tamaas_steps], "step_time": [4.5, 4.5],
              "iterations": [30, 30]}
    return {"n": 64, "steps": steps, "p_max": 0.005, "backend": "numpy", "setup_cpu": 0.4, "ours": ours,
            "rss_start_mb": 100, "rss_before_solve_mb": 110, "rss_peak_mb": 120.4, "tracemalloc_peak_mb": None,
            "fft_pair_f32": {"raw": 0.01, "copies": 0.012}, "fft_pair_estimate": 0.02, "fft_pair_measure": None,
            "fft_pair_numpy": 0.03, "fft_plan_time_estimate": 0.001, "fft_plan_time_measure": None,
            "tamaas": tamaas, "tamaas_note": ""}


def test_summary_columns_and_a_partial_tamaas_run(bench):
    row = bench.compact_row(_result())
    assert list(row) == SUMMARY
    assert row["pair-eq/iter"] == "4.00"  # 0.04 s CPU per iteration / 0.01 s per pair
    assert row["Tamaas steps"] == "2 of 4"
    assert row["CPU ratio Tamaas/ours"] == "10.0 (first 2 steps)"  # 9 s / our 0.9 s to the end of step 2
    assert row["max rel dA/A0"] == "2.0e-01"  # over the two steps Tamaas ran
    wide = bench.wide_row(_result())
    assert wide["tracemalloc peak [MB]"] == "n/a" and wide["FFT pair MEASURE [ms]"] == "n/a"
    assert wide["speed-up wall"] == "11.2 (first 2 steps)"  # 9 s / our 0.8 s of step wall time


def test_summary_without_tamaas(bench):
    r = _result()
    r.update(tamaas=None, tamaas_note="--no-tamaas")
    row = bench.compact_row(r)
    assert list(row) == SUMMARY and row["Tamaas CPU [s]"] == "n/a (--no-tamaas)"


def test_a_tiny_worker_run(bench, monkeypatch):
    monkeypatch.setattr(bench, "_batch", lambda n: 3)
    monkeypatch.setattr(bench, "TRACEMALLOC_MAX_N", 32)
    r = bench.worker(64, 2, 0.005, 1e-8, tamaas=False, plan_repeats=0, methods="", tamaas_steps=0)
    assert r["tracemalloc_peak_mb"] is None and r["plan_solves"] is None and r["method_solves"] is None
    assert r["ours"]["pairs_double"] + r["ours"]["pairs_single"] > 0
    assert len(r["ours"]["step_cpu_cum"]) == 2
    assert r["fft_pair_f32"]["copies"] > 0
    row = bench.compact_row(r)
    assert list(row) == SUMMARY and row["Tamaas CPU [s]"] == "n/a (--no-tamaas)"

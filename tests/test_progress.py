"""A scene's progress and ETA from its plan (the run's jobs) and the finished jobs' benchmark files (issue 62)."""
import json
import os
import time

import pytest

from roughcontact.pipeline.progress import (
    benchmark_seconds,
    estimate,
    log_started,
    main,
    planned_solves,
    read_log_solves,
    read_log_steps,
    scene_progress,
    write_plan,
)

LINE = "2026-11-25 10:00:00,000 INFO step {k}/{n}: p0 = 0.001, A/A0 = 0.01, 12 iterations, {s:.2f} s; about 3 s left"
HEADER = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"


def _log(seconds, n=4):
    return "\n".join(LINE.format(k=k, n=n, s=s) for k, s in enumerate(seconds, start=1)) + "\n"


def _bench(path, seconds):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(HEADER + f"{seconds}\t0:00:01\t170\t346\t110\t135\t0\t0\t41\t1.1\n")


def test_step_lines_are_read_and_a_rerun_starts_over():
    assert read_log_steps(_log([0.5, 1.0, 1.5])) == [0.5, 1.0, 1.5]
    assert read_log_steps(_log([9.0, 9.0]) + "INFO contact ...\n" + _log([0.25])) == [0.25]
    assert read_log_steps("no steps here\n") == []
    assert read_log_solves(_log([3.0]).replace("12 iterations", "3 cases, 12 iterations")) == [(3, 3.0)]


def _plan(jobs, cores=2):
    return {"scene": "demo", "cores": cores,
            "jobs": [{"rule": r, "benchmark": b, "log": None, "weight": w} for r, b, w in jobs]}


def test_left_is_each_rules_pace_times_its_jobs_to_do_over_the_cores(tmp_path):
    """Contact jobs at their own pace (per unit of expected size), the figure rule at the pace of all finished
    jobs while none of its own has finished, spread over the cores."""
    plan = _plan([("contact", f"b/c{i}.tsv", 2.0) for i in range(6)] + [("surface", f"b/s{i}.tsv", 1.0)
                                                                         for i in range(2)]
                 + [("figure", "b/f.tsv", 1.0)])
    started = time.time() - 14.0  # the finished jobs' 28 s over 2 cores: no overhead measured
    for i, s in enumerate([10.0, 14.0]):  # two contact jobs of weight 2: 6 s per unit
        _bench(tmp_path / f"b/c{i}.tsv", s)
    for i in range(2):
        _bench(tmp_path / f"b/s{i}.tsv", 2.0)
    now = started + 14.0
    got = estimate(plan, started, now, tmp_path)
    assert (got.planned, got.done, got.contact_planned, got.contact_done) == (9, 4, 6, 2)
    pace_all = (10 + 14 + 2 + 2) / (2 + 2 + 1 + 1)
    assert got.left == pytest.approx((4 * 2 * 6.0 + 1 * pace_all) / 2)
    # a run whose wall time so far is 1.5 times its finished jobs' time over the cores: the rest is too
    assert estimate(plan, started, started + 21.0, tmp_path).left == pytest.approx(1.5 * got.left)
    assert estimate(plan, started, started + 100.0, tmp_path).left == pytest.approx(3 * got.left)  # held to 3
    assert got.unpaced == ("figure",)
    text = got.text("demo")
    assert text.startswith("scene 'demo': 4 of 9 jobs done (contact 2 of 6): about ")
    assert "left on 2 core(s), from the measured time of each rule's finished jobs; rule(s) figure at the pace" in text


def test_a_running_job_counts_what_it_has_left_and_the_longest_job_bounds_the_estimate(tmp_path):
    plan = _plan([("contact", "b/c0.tsv", 1.0), ("contact", "b/c1.tsv", 1.0)], cores=4)
    plan["jobs"][1]["log"] = "l/c1.log"
    started = time.time() - 100
    _bench(tmp_path / "b/c0.tsv", 40.0)
    (tmp_path / "l").mkdir()
    begun = time.time() - 30
    stamp = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(begun))
    (tmp_path / "l/c1.log").write_text(f"{stamp},000 INFO contact ...\n")
    assert log_started(tmp_path / "l/c1.log") == pytest.approx(int(begun), abs=1)
    got = estimate(plan, started, time.time(), tmp_path)
    assert got.left == pytest.approx(10.0, abs=1.5)  # 40 s a job, 30 s run: one job alone is not split over cores


def test_jobs_of_an_earlier_run_are_not_this_runs_and_unreadable_benchmarks_are_said(tmp_path):
    plan = _plan([("contact", "b/old.tsv", 1.0), ("contact", "b/bad.tsv", 1.0), ("contact", "b/new.tsv", 1.0)])
    _bench(tmp_path / "b/old.tsv", 5.0)
    os.utime(tmp_path / "b/old.tsv", (time.time() - 1000, time.time() - 1000))
    (tmp_path / "b/bad.tsv").write_text("s\th:m:s\n")  # a truncated benchmark file
    _bench(tmp_path / "b/new.tsv", 3.0)
    assert benchmark_seconds(tmp_path / "b/bad.tsv") is None and benchmark_seconds(tmp_path / "b/no.tsv") is None
    got = estimate(plan, time.time() - 100, time.time(), tmp_path)
    assert (got.done, got.unknown) == (2, 1) and got.left == pytest.approx(3.0)
    assert got.text("demo").endswith("; 1 finished job(s) whose benchmark file cannot be read, counted done at an "
                                     "unknown time")
    assert estimate(_plan([("contact", "b/x.tsv", 1.0)]), time.time(), time.time(), tmp_path).text("demo") == (
        "scene 'demo': 0 of 1 jobs done (contact 0 of 1); no pace yet (no job has finished)")


def test_scene_progress_reads_the_plan_the_workflow_writes(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scene = tmp_path / "results" / "demo"
    jobs = [("contact", "results/demo/benchmarks/contact/a.tsv", "results/demo/logs/contact/a.log", 5),
            ("figure", "results/demo/benchmarks/figure_kappa.tsv", None, None), ("all", None, None, None)]
    write_plan(scene, "demo", jobs, cores=2)
    plan = json.loads((scene / "logs" / "plan.json").read_text())
    assert plan["cores"] == 2 and [j["rule"] for j in plan["jobs"]] == ["contact", "figure"]  # no benchmark: not a job
    assert [j["weight"] for j in plan["jobs"]] == [5.0, 1.0]
    main(["results/demo"])
    assert capsys.readouterr().out == "scene 'demo': 0 of 2 jobs done (contact 0 of 1); no pace yet (no job has " \
                                      "finished)\n"
    _bench(scene / "benchmarks" / "contact" / "a.tsv", 7.0)
    _bench(scene / "benchmarks" / "figure_kappa.tsv", 2.0)
    name, got = scene_progress(scene)
    assert name == "demo" and got.text("demo") == "scene 'demo': 2 of 2 jobs done (contact 1 of 1), all"
    (tmp_path / "other").mkdir()
    with pytest.raises(SystemExit) as stop:
        main([str(tmp_path / "other")])
    assert stop.value.code == 2
    assert "plan.json not found: no run of this scene has started here" in capsys.readouterr().err
    (scene / "logs" / "plan.json").write_text(json.dumps({"scene": "demo", "cores": 2, "jobs": [{"rule": 1}]}))
    with pytest.raises(SystemExit) as stop:
        main(["results/demo"])
    assert stop.value.code == 2 and "jobs[0] is {'rule': 1}, not a job" in capsys.readouterr().err


def test_planned_solves_counts_a_scenes_load_steps():
    scene = {"contact": {"grid": {"k_l": ["1"], "k_s": ["8"], "H": ["0.5", "0.7"]}, "seeds": 3,
                         "load": {"n_steps": 4}}}
    assert planned_solves(scene) == 2 * 3 * 4 and planned_solves({"representativity": {}}) == 0

"""A scene's progress and ETA from its plan and its contact jobs' step lines."""
import json

import pytest

from roughcontact.pipeline.progress import (
    Progress,
    main,
    planned_solves,
    read_log_solves,
    read_log_steps,
    scene_progress,
    write_plan,
)

LINE = "2026-11-25 10:00:00,000 INFO step {k}/{n}: p0 = 0.001, A/A0 = 0.01, 12 iterations, {s:.2f} s; about 3 s left"


def _log(seconds, n=4):
    return "\n".join(LINE.format(k=k, n=n, s=s) for k, s in enumerate(seconds, start=1)) + "\n"


def test_step_lines_are_read_and_a_rerun_starts_over():
    assert read_log_steps(_log([0.5, 1.0, 1.5])) == [0.5, 1.0, 1.5]
    assert read_log_steps(_log([9.0, 9.0]) + "INFO contact ...\n" + _log([0.25])) == [0.25]
    assert read_log_steps("no steps here\n") == []


def test_eta_is_the_rest_at_the_mean_pace_over_the_cores():
    p = Progress(planned=100, done=20, seconds=40.0, cores=2)
    assert p.left_seconds() == pytest.approx(80 * 2.0 / 2)
    assert p.text("demo") == ("scene 'demo': 20 of 100 contact solves done (20 %), 2 s a solve: "
                              "about 1 min 20 s left on 2 core(s)")
    assert Progress(100, 0, 0.0, 2).text("demo").endswith("no pace yet")
    assert Progress(10, 10, 5.0, 1).text("demo").endswith("(all)")
    assert "1 h 23 min" in Progress(10_000, 1, 1.0, 2).text("x")


def test_scene_progress_reads_plan_and_logs(tmp_path, capsys):
    scene = {"contact": {"grid": {"k_l": ["1"], "k_s": ["8"], "H": ["0.5", "0.7"]}, "seeds": 3,
                         "load": {"n_steps": 4}}}
    assert planned_solves(scene) == 2 * 3 * 4
    write_plan(tmp_path, "demo", scene, cores=2)
    assert json.loads((tmp_path / "logs" / "plan.json").read_text()) == {"cores": 2, "scene": "demo", "solves": 24}
    logs = tmp_path / "logs" / "contact"
    logs.mkdir()
    (logs / "a.log").write_text(_log([1.0, 1.0, 1.0, 1.0]))
    (logs / "b.log").write_text(_log([2.0, 2.0]))
    name, got = scene_progress(tmp_path)
    assert name == "demo" and (got.done, got.seconds, got.planned) == (6, 8.0, 24)
    main([str(tmp_path)])
    assert "6 of 24 contact solves done (25 %)" in capsys.readouterr().out
    # a batch's step (contact.solver.batch) counts as its cases' solves
    batch_log = tmp_path / "logs" / "contact_batch" / "c.log"
    batch_log.parent.mkdir()
    batch_log.write_text(_log([3.0]).replace("12 iterations", "3 cases, 12 iterations"))
    assert read_log_solves(batch_log.read_text()) == [(3, 3.0)]
    _, got = scene_progress(tmp_path)
    assert (got.done, got.seconds) == (9, 11.0)
    (tmp_path / "other").mkdir()
    with pytest.raises(SystemExit) as stop:
        main([str(tmp_path / "other")])
    assert stop.value.code == 2
    assert "plan.json not found: no run of this scene has started here" in capsys.readouterr().err
    assert planned_solves({"representativity": {}}) == 0

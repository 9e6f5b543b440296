"""roughcontact.pipeline.runcost: a run's cost summed from Snakemake's benchmark files and the jobs' logs."""

import pytest

from roughcontact.pipeline import runcost

HEADER = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"


def _bench(path, wall, cpu, rss, load=50.0):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(HEADER + f"{wall}\t0:00:01\t{rss}\t1\t1\t1\t0\t0\t{load}\t{cpu}\n")


@pytest.fixture
def run(tmp_path):
    b = tmp_path / "results" / "s" / "benchmarks"
    _bench(b / "contact" / "kl16_ks32_H0.8_s0.tsv", 70.0, 40.0, 290.0)
    _bench(b / "contact" / "kl16_ks32_H0.8_s1.tsv", 50.0, 30.0, 300.0)
    _bench(b / "contact" / "kl1_ks32_H0.8_s0.tsv", 60.0, 110.0, 280.0)
    _bench(b / "fit_cel.tsv", 90.0, 74.0, 155.0)
    _bench(b / "accuracy" / "N512" / "kl16_ks32_H0.8_s0.tsv", 5.0, 4.0, 100.0)
    return tmp_path / "results" / "s"


def test_costs_are_summed_per_rule(run):
    costs = {c.rule: c for c in runcost.run_cost(run)}
    assert sorted(costs) == ["accuracy", "contact", "fit_cel"]
    c = costs["contact"]
    assert (c.jobs, c.cpu_total, c.cpu_max, c.max_rss) == (3, 180.0, 110.0, 300.0)
    assert c.cpu_mean == pytest.approx(60.0) and c.cpu_median == 40.0 and c.wall_mean == pytest.approx(60.0)
    assert costs["accuracy"].jobs == 1  # nested folders count for the rule that holds them


def test_markdown_has_a_row_per_rule_and_a_total(run, capsys):
    runcost.main([str(run)])
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("| rule | jobs | CPU total [h]")
    # no job logged its exact cost: every CPU total is Snakemake's sample, a lower bound
    assert out[3] == "| contact | 3 | ≥ 0.05 | 60.0 / 40.0 / 110.0 | 0.05 | 60.0 | 300 |"
    assert out[-3] == "| all | 5 | ≥ 0.07 | | 0.08 | | 300 |"
    assert out[-1].startswith("≥: 5 of 5 jobs have no exact CPU line in their log")


def _log(run, rel, *lines):
    path = run / "logs" / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(f"2026-11-23 01:00:00,000 INFO {line}\n" for line in lines))


def test_a_jobs_exact_cost_comes_from_the_last_line_of_its_log(run, capsys):
    # Snakemake samples CPU every 30 s; run_logged's last log line is the exact figure
    from roughcontact.pipeline.io import JOB_COST_FORMAT

    exact = JOB_COST_FORMAT.format(cpu=62.5, rss=333.0)
    _log(run, "contact/kl16_ks32_H0.8_s0.log", "step 1/30", exact)
    _log(run, "contact/kl16_ks32_H0.8_s1.log", exact, "ERROR a later failure")  # not the last line: sampled
    _log(run, "contact/kl1_ks32_H0.8_s0.log", JOB_COST_FORMAT.format(cpu=111.0, rss=10.0))
    _log(run, "fit_cel.log", JOB_COST_FORMAT.format(cpu=75.25, rss=150.0))
    _log(run, "accuracy/N512/kl16_ks32_H0.8_s0.log", JOB_COST_FORMAT.format(cpu=4.5, rss=90.0))
    costs = {c.rule: c for c in runcost.run_cost(run)}
    c = costs["contact"]
    assert (c.cpu_total, c.cpu_max, c.max_rss, c.sampled) == (62.5 + 30.0 + 111.0, 111.0, 333.0, 1)
    assert (costs["fit_cel"].cpu_total, costs["fit_cel"].sampled) == (75.25, 0)
    assert (costs["accuracy"].cpu_total, costs["accuracy"].max_rss) == (4.5, 90.0)  # nested folders too
    runcost.main([str(run)])
    out = capsys.readouterr().out.splitlines()
    assert "| fit_cel | 1 | 0.02 | 75.2 / 75.2 / 75.2 | 0.03 | 90.0 | 150 |" in out
    assert out[-1].startswith("≥: 1 of 5 jobs have no exact CPU line")
    _log(run, "contact/kl16_ks32_H0.8_s1.log", JOB_COST_FORMAT.format(cpu=31.0, rss=1.0))
    runcost.main([str(run)])
    out = capsys.readouterr().out.splitlines()
    assert out[-1] == "| all | 5 | 0.08 | | 0.08 | | 333 |" and "≥" not in "".join(out)


@pytest.mark.parametrize("body, message", [
    ("", "empty benchmark file"),
    ("s\tcpu_time\tmax_rss\n1\t2\t3\n", "no column 'mean_load'"),
    (HEADER + "1\t0:00:01\tNA\t1\t1\t1\t0\t0\t50\t2\n", "max_rss = 'NA' is not a number"),
    (HEADER + "1\t0:00:01\tnan\t1\t1\t1\t0\t0\t50\t2\n", "max_rss = 'nan' is not a finite number"),
])
def test_a_bad_benchmark_file_is_named(tmp_path, body, message):
    path = tmp_path / "benchmarks" / "contact" / "x.tsv"
    path.parent.mkdir(parents=True)
    path.write_text(body)
    with pytest.raises(ValueError, match=message) as err:
        runcost.run_cost(tmp_path)
    assert str(path) in str(err.value)


def test_a_run_without_benchmarks_says_so(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        runcost.main([str(tmp_path)])
    assert stop.value.code == 2
    assert "no such directory" in capsys.readouterr().err
    (tmp_path / "benchmarks").mkdir()
    with pytest.raises(SystemExit) as stop:
        runcost.main([str(tmp_path)])
    assert stop.value.code == 1
    assert "no job has finished" in capsys.readouterr().err


def _adopted(run, name, source_file, content=b"copy"):
    """A case file of ``run`` as adoption wrote it, and its manifest row."""
    import hashlib

    (run / "contact").mkdir(exist_ok=True)
    (run / "contact" / name).write_bytes(content)
    return f"{name}\t{source_file}\ta\t{hashlib.sha256(content).hexdigest()}\n"


def test_adopted_cases_count_with_their_cost_in_the_source_run(run, capsys):
    # three cases adopted from run "src" (one path absolute, the others relative to the working directory)
    src = run.parents[1] / "results" / "src"
    for seed, (cpu, rss) in enumerate([(45.0, 310.0), (35.0, 290.0), (99.0, 999.0)]):
        _bench(src / "benchmarks" / "contact" / f"kl2_ks32_H0.8_s{seed}.tsv", 80.0, cpu, rss)
    _bench(src / "benchmarks" / "surface" / "kl2_ks32_H0.8_s1.tsv", 2.0, 1.5, 180.0)  # s0's surface: no file
    rows = [_adopted(run, "kl2_ks32_H0.8_s0.nc", src / "contact" / "kl2_ks32_H0.8_s0.nc"),
            _adopted(run, "kl2_ks32_H0.8_s1.nc", "results/src/contact/kl2_ks32_H0.8_s1.nc"),
            _adopted(run, "kl2_ks32_H0.8_s2.nc", "results/src/contact/kl2_ks32_H0.8_s2.nc")]
    (run / "adopted.tsv").write_text("case_file\tsource_file\tsource_sha256\tsha256\n" + "".join(rows))
    (run / "contact" / "kl2_ks32_H0.8_s2.nc").write_bytes(b"solved here since")  # no longer the copy
    costs = {c.rule: c for c in runcost.run_cost(run)}
    assert costs["contact"].jobs == 3
    assert (costs["contact (adopted)"].jobs, costs["contact (adopted)"].cpu_total) == (2, 80.0)
    assert (costs["surface (adopted)"].jobs, costs["surface (adopted)"].cpu_total) == (1, 1.5)
    runcost.main([str(run)])
    out = capsys.readouterr().out.splitlines()
    assert "| contact (adopted) | 2 | ≥ 0.02 | 40.0 / 40.0 / 45.0 | 0.04 | 80.0 | 310 |" in out
    assert out[-3] == "| all | 8 | ≥ 0.09 | | 0.12 | | 310 |"
    # the source run's log of an adopted case gives its exact cost
    from roughcontact.pipeline.io import JOB_COST_FORMAT

    _log(src, "contact/kl2_ks32_H0.8_s0.log", JOB_COST_FORMAT.format(cpu=70.0, rss=320.0))
    adopted = {c.rule: c for c in runcost.run_cost(run)}["contact (adopted)"]
    assert (adopted.cpu_total, adopted.max_rss, adopted.sampled) == (105.0, 320.0, 1)
    # a source without the case's benchmark file is named
    (src / "benchmarks" / "contact" / "kl2_ks32_H0.8_s1.tsv").unlink()
    with pytest.raises(ValueError, match=r"adopted.tsv: adopted case kl2_ks32_H0.8_s1.nc has no benchmark file"):
        runcost.run_cost(run)

"""What a run cost, from the logs and benchmark files Snakemake kept of its jobs.

Every rule of the workflow has a ``benchmark:`` directive, so each finished job leaves a
one-row TSV under ``results/{scene}/benchmarks/`` (``{rule}.tsv`` for a rule with one job,
``{rule}/{case}.tsv`` for one per case) with its wall time ``s``, CPU time ``cpu_time``
[s], peak resident memory ``max_rss`` [MiB] and ``mean_load`` [% of one core]. This
module sums them per rule, so a study's cost is measured rather than estimated::

    python -m roughcontact.pipeline.runcost results/paper            # markdown table on stdout

Snakemake measures CPU and memory by sampling the job every 0.5 s for its first 15 s, then
every 30 s (snakemake/snakemake#851), and keeps the last sample: ``cpu_time`` misses up to
30 s of CPU a job (22 % of the paper grid's CPU, measured). So each job's CPU and
peak memory are read from the last line of its log (``results/{scene}/logs/``, same path as
the benchmark file), where :func:`roughcontact.pipeline.io.run_logged` writes the job process's exact
figures (getrusage). A job whose log lacks that line (run by older code) keeps the sampled
value, a lower bound: its rule's CPU total is then printed with ``≥`` and counted in the
note under the table. Wall time is exact either way.

Only finished jobs have a file: on an interrupted run the table is the cost so far. A rerun
job overwrites its file; files of jobs a later run no longer plans (an older grid or rule
layout) stay and are counted, so measure a run in a fresh ``results/{scene}``.

Cases the run adopted from another (:mod:`roughcontact.pipeline.adopt`, listed in ``adopted.tsv``)
have no benchmark file of their own: their cost where they were computed, the source
run's benchmark file (and log) of each, is a row of its own (``contact (adopted)``).
"""

from __future__ import annotations

import argparse
import csv
import math
import statistics
from dataclasses import dataclass
from pathlib import Path

from ..core.cli import input_errors
from ..core.files import file_sha256
from .adopt import MANIFEST
from .io import JOB_COST_PATTERN

#: Columns of Snakemake's benchmark TSV this module reads.
COLUMNS = ("s", "cpu_time", "max_rss", "mean_load")


@dataclass(frozen=True)
class RuleCost:
    """The summed cost of one rule's finished jobs (times in s, memory in MiB)."""

    rule: str
    jobs: int
    cpu_total: float
    cpu_mean: float
    cpu_median: float
    cpu_max: float
    wall_total: float
    max_rss: float
    #: jobs whose CPU and memory are Snakemake's samples (lower bounds): no exact line in their log
    sampled: int

    @property
    def wall_mean(self) -> float:
        return self.wall_total / self.jobs


def read_benchmark(path: str | Path) -> dict[str, float]:
    """The first row of one Snakemake benchmark file, the :data:`COLUMNS` as floats.

    Raises ValueError naming the file when it is empty, lacks a column or holds a value
    that is not a finite number (Snakemake writes ``NA`` when it could not measure).
    """
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            rows = list(csv.DictReader(handle, delimiter="\t"))
    except (UnicodeDecodeError, csv.Error) as exc:
        raise ValueError(f"{path}: not a Snakemake benchmark file (tab-separated text): {exc}") from None
    if not rows:
        raise ValueError(f"{path}: empty benchmark file (no row under the header)")
    row = {}
    for col in COLUMNS:
        if col not in rows[0]:
            raise ValueError(f"{path}: no column {col!r}; a Snakemake benchmark file has {', '.join(COLUMNS)}")
        try:
            row[col] = float(rows[0][col])
        except (TypeError, ValueError):
            raise ValueError(f"{path}: {col} = {rows[0][col]!r} is not a number") from None
        if not math.isfinite(row[col]):
            raise ValueError(f"{path}: {col} = {rows[0][col]!r} is not a finite number")
        if row[col] < 0:
            raise ValueError(f"{path}: {col} = {rows[0][col]!r} is negative; a time, memory or load is >= 0 "
                             "(the file is damaged: remove it, or rerun its job)")
    return row


def log_of(bench: Path) -> Path:
    """The log of the job whose benchmark file is ``bench``: ``logs/`` for ``benchmarks/``, ``.log`` for ``.tsv``."""
    root = next((p for p in bench.parents if p.name == "benchmarks"), None)
    if root is None:
        raise ValueError(f"{bench}: not under a benchmarks/ folder")
    return root.parent / "logs" / bench.relative_to(root).with_suffix(".log")


def exact_cost(log: Path) -> tuple[float, float] | None:
    """The exact (CPU [s], peak RSS [MiB]) a job's log ends with, or None (no log, no such line)."""
    try:
        lines = log.read_text(errors="replace").splitlines()
    except OSError:
        return None
    match = JOB_COST_PATTERN.search(lines[-1]) if lines else None
    return (float(match[1]), float(match[2])) if match else None


def read_job(bench: Path) -> dict[str, float]:
    """One job's cost: its benchmark row, with CPU and peak RSS from its log where exact.

    ``exact`` is 1.0 where the log had the exact line, 0.0 where ``cpu_time`` and
    ``max_rss`` are Snakemake's samples.
    """
    row = read_benchmark(bench)
    cost = exact_cost(log_of(bench))
    if cost is not None:
        row["cpu_time"], row["max_rss"] = cost
    row["exact"] = float(cost is not None)
    return row


def rule_files(benchmarks: str | Path) -> dict[str, list[Path]]:
    """Benchmark files by rule: ``{rule}.tsv`` and ``{rule}/**/*.tsv`` under ``benchmarks``."""
    root = Path(benchmarks)
    if not root.is_dir():
        raise ValueError(f"{root}: no such directory (a run's benchmarks are in results/<scene>/benchmarks)")
    out: dict[str, list[Path]] = {}
    for path in sorted(root.rglob("*.tsv")):
        rel = path.relative_to(root)
        rule = rel.stem if len(rel.parts) == 1 else rel.parts[0]
        out.setdefault(rule, []).append(path)
    return out


#: Per-case rules whose source-run benchmark files an adopted contact case brings: its solve
#: (required) and the generation of the surface it solved (when the source run kept a file).
ADOPTED_RULES = ("contact", "surface")


def _still_adopted(results: Path, row: dict) -> bool:
    """Whether the case file of a manifest row is still the copy adoption wrote."""
    target = results / Path(row["source_file"]).parent.name / row["case_file"]
    return target.is_file() and file_sha256(target) == row["sha256"]


def adopted_files(results: str | Path) -> dict[str, list[Path]]:
    """Benchmark files of the cases ``results`` adopted, in their source runs, by ``"{rule} (adopted)"``.

    A relative source path in the manifest is relative to the working directory that holds
    ``results`` (``results/{scene}``). A case whose file is no longer the adopted copy (its
    sha256 differs: the run has since solved it itself, and has its own benchmark file) is
    left out. Raises ValueError naming the manifest and the case when the source run has no
    benchmark file of the case's solve.
    """
    results = Path(results)
    manifest = results / MANIFEST
    if not manifest.is_file():
        return {}
    out: dict[str, list[Path]] = {}
    with manifest.open(newline="") as handle:
        for row in csv.DictReader(handle, delimiter="\t"):
            if not _still_adopted(results, row):
                continue
            src = Path(row["source_file"])
            src = src if src.is_absolute() else results.resolve().parents[1] / src
            for rule in ADOPTED_RULES:
                bench = src.parents[1] / "benchmarks" / rule / f"{src.stem}.tsv"
                if bench.is_file():
                    out.setdefault(f"{rule} (adopted)", []).append(bench)
                elif rule == "contact":
                    raise ValueError(f"{manifest}: adopted case {row['case_file']} has no benchmark file {bench} "
                                     "in its source run")
    return out


def summarize(rows_by_rule: dict[str, list[dict[str, float]]]) -> list[RuleCost]:
    """One :class:`RuleCost` per rule with at least one job, rules sorted by name."""
    out = []
    for rule in sorted(rows_by_rule):
        rows = rows_by_rule[rule]
        if not rows:
            continue
        cpu = [r["cpu_time"] for r in rows]
        wall = [r["s"] for r in rows]
        sampled = sum(1 for r in rows if not r["exact"])
        out.append(RuleCost(rule, len(rows), sum(cpu), statistics.fmean(cpu), statistics.median(cpu), max(cpu),
                            sum(wall), max(r["max_rss"] for r in rows), sampled))
    return out


def run_cost(results: str | Path) -> list[RuleCost]:
    """The cost per rule of the run whose outputs are in ``results`` (``results/{scene}``)."""
    files = {**rule_files(Path(results) / "benchmarks"), **adopted_files(results)}
    return summarize({rule: [read_job(p) for p in paths] for rule, paths in files.items()})


def _hours(seconds: float, sampled: int) -> str:
    return f"{'≥ ' if sampled else ''}{seconds / 3600:.2f}"


def markdown(costs: list[RuleCost]) -> str:
    """The costs as a markdown table, with a total row (CPU and wall in hours there).

    A CPU total marked ``≥`` includes jobs with only Snakemake's sampled CPU (a lower
    bound); a note under the table counts them.
    """
    lines = ["| rule | jobs | CPU total [h] | CPU per job, mean / median / max [s] | wall total [h] "
             "| wall per job, mean [s] | peak RSS [MiB] |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for c in costs:
        lines.append(f"| {c.rule} | {c.jobs} | {_hours(c.cpu_total, c.sampled)} | {c.cpu_mean:.1f} / "
                     f"{c.cpu_median:.1f} / {c.cpu_max:.1f} | {c.wall_total / 3600:.2f} | {c.wall_mean:.1f} "
                     f"| {c.max_rss:.0f} |")
    if costs:
        jobs, sampled = sum(c.jobs for c in costs), sum(c.sampled for c in costs)
        lines.append(f"| all | {jobs} | {_hours(sum(c.cpu_total for c in costs), sampled)} | | "
                     f"{sum(c.wall_total for c in costs) / 3600:.2f} | | {max(c.max_rss for c in costs):.0f} |")
        if sampled:
            lines.append(f"\n≥: {sampled} of {jobs} jobs have no exact CPU line in their log (older code); "
                         "theirs is Snakemake's sample, which misses up to 30 s of CPU a job.")
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(prog="python -m roughcontact.pipeline.runcost", description=__doc__.split("\n")[0])
    ap.add_argument("results", help="a run's output folder, results/<scene>")
    args = ap.parse_args(argv)
    with input_errors(ap):
        costs = run_cost(args.results)
    if not costs:
        ap.exit(1, f"error: no benchmark files under {Path(args.results) / 'benchmarks'}: no job has finished\n")
    print(markdown(costs), end="")


if __name__ == "__main__":
    main()

"""How far a scene's run has got, and about how long the rest will take, from the jobs' measured times.

When a run starts, the workflow writes its plan, ``results/{scene}/logs/plan.json`` (:func:`write_plan`): every
job Snakemake is about to run for the scene (its rule, its benchmark file, its log, and its ``runtime``
resource, the size the workflow expects of it: :func:`roughcontact.pipeline.targets.contact_runtime_min` and its
kin grow with the grid), and the cores the run was given. A job is done when its benchmark file, which
Snakemake writes when the job ends, is newer than the plan; the file's ``s`` column is the job's wall time.
:func:`scene_progress` estimates what is left per rule: the planned jobs still to do, weighted by their
expected size, at the measured seconds per unit of size of the rule's finished jobs (a rule with none finished
yet: at the pace of all finished jobs); a running job counts with the time it has already had taken off. The
sum is spread over the cores, and is never less than the longest job left; it is then scaled by the run's
measured overhead, its wall time so far over its finished jobs' time spread over the cores (Snakemake's
scheduling, what a job spends outside its benchmark, cores idle while a chain of single jobs runs; between 1 and
3). Every kind of job is counted:
contact cases, contact batches (``contact.solver.batch``) and cases over MPI ranks (``solver.ranks``), the
surfaces, aggregates, fits, figures and the report.

Until issue 62 the estimate counted only the contact solves' own seconds (the steps' lines): it missed each
job's start-up and writing, and every other rule, and said "about 2 s left" with 45 s to go.
``benchmarks/bench_progress.py`` measures the estimate against the time actually left.

Each contact job logs the scene's estimate when it ends, and ``python -m roughcontact.pipeline.progress
results/SCENE`` prints it at any time (from another terminal while a run goes on).
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
import re
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ..case.progress import duration_text
from ..core.cli import input_errors, read_json_object, require_folder
from ..core.files import write_text_atomic
from .sources import source_of

#: The per-step line of a contact job's log (workflow/scripts/contact.py), or of a batch's (``B cases``).
STEP_LINE = re.compile(r"step (\d+)/(\d+): .*?, (?:(\d+) cases, )?\d+ iterations, ([0-9.]+) s")
PLAN_FILE = "plan.json"
#: The rule whose jobs solve contact cases (the progress line counts its jobs apart): one per group.
CONTACT_RULES = ("contact",)
#: The time stamp that begins each line of a job's log (roughcontact.pipeline.io.run_logged).
LOG_TIME = re.compile(r"^(\d{4}-\d\d-\d\d \d\d:\d\d:\d\d),(\d{3}) ")


def planned_solves(scene: Mapping) -> int:
    """Load steps the contact study of a validated scene solves: its source's cases x ``n_steps``; 0 without one."""
    if "contact" not in scene:
        return 0
    return len(source_of(scene).cases(scene, "contact")) * scene["contact"]["load"]["n_steps"]


def write_plan(scene_dir: str | Path, scene_name: str, jobs: Iterable[tuple[str, str, str | None, float | None]],
               cores: int) -> Path:
    """Write ``{scene_dir}/logs/plan.json``: the scene, the jobs this run will run for it, and the run's cores.

    ``jobs``: ``(rule, benchmark file, log file or None, runtime resource or None)`` of each job Snakemake is
    about to run (the workflow's ``onstart`` reads them from Snakemake's DAG); jobs without a benchmark file
    (the ``all`` rule) are left out. The file's modification time is the run's start.
    """
    rows = [{"rule": str(rule), "benchmark": str(bench), "log": None if log is None else str(log),
             "weight": _weight(runtime)} for rule, bench, log, runtime in jobs if bench]
    plan = {"scene": scene_name, "cores": max(1, int(cores or 1)), "jobs": sorted(rows, key=lambda r: r["benchmark"])}
    return write_text_atomic(Path(scene_dir) / "logs" / PLAN_FILE, json.dumps(plan, sort_keys=True, indent=0) + "\n")


def _weight(runtime) -> float:
    """A job's expected size from its ``runtime`` resource (minutes), 1 without one."""
    try:
        value = float(runtime)
    except (TypeError, ValueError):
        return 1.0
    return value if value > 0 else 1.0


@dataclass(frozen=True)
class Progress:
    """A scene's run so far: jobs planned and done (all, and the contact jobs), wall time left, cores.

    ``left`` is None before any job has finished (no pace yet); ``unknown`` counts the finished jobs whose
    benchmark file could not be read (left out of the pace, said in :meth:`text`).
    """

    planned: int
    done: int
    contact_planned: int
    contact_done: int
    left: float | None
    cores: int
    unknown: int = 0
    unpaced: tuple[str, ...] = field(default=())

    def left_seconds(self) -> float | None:
        """Estimated wall time left [s]; None before any job finished."""
        return self.left

    def text(self, scene: str) -> str:
        """One line for a log or a terminal."""
        head = f"scene {scene!r}: {self.done} of {self.planned} jobs done"
        if self.contact_planned:
            head += f" (contact {self.contact_done} of {self.contact_planned})"
        unknown = (f"; {self.unknown} finished job(s) whose benchmark file cannot be read, counted done at an "
                   "unknown time" if self.unknown else "")
        if self.done >= self.planned:
            return head + ", all" + unknown
        if self.left is None:
            return head + "; no pace yet (no job has finished)" + unknown
        assumed = (f"; rule(s) {', '.join(self.unpaced)} at the pace of the others (none of theirs finished yet)"
                   if self.unpaced else "")
        return (f"{head}: about {duration_text(self.left)} left on {self.cores} core(s), from the measured time of "
                f"each rule's finished jobs{assumed}{unknown}")


def read_log_steps(text: str) -> list[float]:
    """Seconds of each load step a contact log reports, in order (the last run's, if it ran twice)."""
    return [seconds for _, seconds in read_log_solves(text)]


def read_log_solves(text: str) -> list[tuple[int, float]]:
    """``(cases, seconds)`` of each load step a contact or contact batch log reports, in order (the last run's).

    A single case's step is one solve; a batch's step line names how many cases it solved together.
    """
    steps: dict[int, tuple[int, float]] = {}
    for match in STEP_LINE.finditer(text):
        k = int(match.group(1))
        if k == 1:
            steps = {}  # a log that ran again starts over
        steps[k] = (int(match.group(3) or 1), float(match.group(4)))
    return [steps[k] for k in sorted(steps)]


def read_plan(path: str | Path) -> dict:
    """A plan file written by :func:`write_plan`, checked (``ValueError`` naming the file and the key otherwise)."""
    plan = read_json_object(path, {"scene": str, "cores": int, "jobs": list})
    if plan["cores"] < 1:
        raise ValueError(f"{path}: cores = {plan['cores']} must be >= 1; the workflow rewrites this file when a run "
                         "starts")
    for i, job in enumerate(plan["jobs"]):
        if not (isinstance(job, dict) and isinstance(job.get("rule"), str) and isinstance(job.get("benchmark"), str)
                and isinstance(job.get("weight"), (int, float))):
            raise ValueError(f"{path}: jobs[{i}] is {job!r}, not a job (rule, benchmark, log, weight); the workflow "
                             "rewrites this file when a run starts")
    return plan


def benchmark_seconds(path: str | Path) -> float | None:
    """The wall time [s] of the job a Snakemake benchmark file records (its ``s`` column), None if unreadable."""
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh, delimiter="\t"))
        value = float(rows[-1]["s"])
    except (OSError, UnicodeDecodeError, csv.Error, IndexError, KeyError, TypeError, ValueError):
        return None
    return value if value >= 0 else None


def log_started(path: str | Path) -> float | None:
    """When a job's log began (its first line's time stamp, local time, as seconds since the epoch), or None."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            first = fh.readline()
    except OSError:
        return None
    match = LOG_TIME.match(first)
    if not match:
        return None
    stamp = datetime.datetime.strptime(match.group(1), "%Y-%m-%d %H:%M:%S")
    return stamp.timestamp() + int(match.group(2)) / 1000


def estimate(plan: dict, started: float, now: float, base: Path = Path(".")) -> Progress:
    """:class:`Progress` of a ``plan`` (:func:`read_plan`) that started at ``started`` (epoch seconds), at ``now``.

    Paths in the plan are relative to ``base`` (the workflow's folder). See the module's docstring for the rule.
    """
    finished: dict[str, list[tuple[float, float]]] = {}  # rule -> (weight, seconds) of its finished jobs
    waiting: list[tuple[str, float, float]] = []  # (rule, weight, seconds already run) of the jobs not finished
    done = contact_done = unknown = 0
    for job in plan["jobs"]:
        bench = base / job["benchmark"]
        if bench.is_file() and bench.stat().st_mtime >= started - 1.0:
            done += 1
            contact_done += job["rule"] in CONTACT_RULES
            seconds = benchmark_seconds(bench)
            if seconds is None:
                unknown += 1
            else:
                finished.setdefault(job["rule"], []).append((job["weight"], seconds))
            continue
        ran = 0.0
        log = base / job["log"] if job.get("log") else None
        if log is not None and log.is_file() and log.stat().st_mtime >= started - 1.0:
            begun = log_started(log)
            ran = max(now - begun, 0.0) if begun is not None and begun >= started - 1.0 else 0.0
        waiting.append((job["rule"], job["weight"], ran))
    contact_planned = sum(job["rule"] in CONTACT_RULES for job in plan["jobs"])
    pace_all = _pace([x for jobs in finished.values() for x in jobs])
    if pace_all is None:
        left = None if waiting else 0.0
        return Progress(len(plan["jobs"]), done, contact_planned, contact_done, left, plan["cores"], unknown)
    lefts, unpaced = [], set()
    for rule, weight, ran in waiting:
        pace = _pace(finished.get(rule, []))
        if pace is None:
            pace = pace_all
            unpaced.add(rule)
        lefts.append(max(weight * pace - ran, 0.0))
    left = max(sum(lefts) / plan["cores"], max(lefts, default=0.0)) * _overhead(finished, plan["cores"],
                                                                                 now - started)
    return Progress(len(plan["jobs"]), done, contact_planned, contact_done, left, plan["cores"], unknown,
                    tuple(sorted(unpaced)))


#: Finished jobs before :func:`_overhead` is measured, and the range it is held to.
OVERHEAD_JOBS, OVERHEAD_RANGE = 3, (1.0, 3.0)


def _overhead(finished: dict[str, list[tuple[float, float]]], cores: int, elapsed: float) -> float:
    """The run's wall time so far over its finished jobs' own time spread over the cores: what scheduling, job
    start-up outside the benchmark and idle cores (a chain of single jobs) add, as measured; 1 until
    :data:`OVERHEAD_JOBS` jobs have finished, held to :data:`OVERHEAD_RANGE`."""
    seconds = [s for jobs in finished.values() for _, s in jobs]
    if len(seconds) < OVERHEAD_JOBS or sum(seconds) <= 0:
        return 1.0
    low, high = OVERHEAD_RANGE
    return min(max(elapsed / (sum(seconds) / cores), low), high)


def _pace(jobs: list[tuple[float, float]]) -> float | None:
    """Seconds per unit of expected size of finished ``(weight, seconds)`` jobs, None without any."""
    weight = sum(w for w, _ in jobs)
    return sum(s for _, s in jobs) / weight if jobs and weight > 0 else None


def scene_progress(scene_dir: str | Path, now: float | None = None) -> tuple[str, Progress] | None:
    """The scene's name and :class:`Progress` from its plan and its jobs' benchmark files; None without a plan.

    ``scene_dir`` is ``results/{scene}``; the plan's paths are relative to the workflow's folder, two levels up.
    """
    scene_dir = Path(scene_dir)
    plan_path = scene_dir / "logs" / PLAN_FILE
    if not plan_path.is_file():
        return None
    plan = read_plan(plan_path)
    base = scene_dir.parent.parent
    return plan["scene"], estimate(plan, plan_path.stat().st_mtime, time.time() if now is None else now, base)


def main(argv=None) -> None:
    """``python -m roughcontact.pipeline.progress results/SCENE``: print how far the scene's run has got."""
    ap = argparse.ArgumentParser(prog="python -m roughcontact.pipeline.progress", description=__doc__.split("\n\n")[0])
    ap.add_argument("scene_dir", type=Path, help="the scene's results folder, e.g. results/demo")
    args = ap.parse_args(argv)
    with input_errors(ap):
        require_folder(args.scene_dir, "a scene's results folder, e.g. results/demo")
        got = scene_progress(args.scene_dir)
    if got is None:
        ap.exit(2, f"error: {args.scene_dir / 'logs' / PLAN_FILE} not found: no run of this scene has "
                "started here (the workflow writes it when a run starts)\n")
    print(got[1].text(got[0]))


if __name__ == "__main__":
    main()

"""How far a scene's contact study has got, and about how long the rest will take.

Each contact job logs one line per load step (``step k/n: ..., 12 iterations, 0.41 s; ...``); a contact
batch job (``contact.solver.batch``, ``logs/contact_batch/``) one line per load step of all its cases
(``step k/n: ..., 4 cases, 12 iterations, 0.41 s; ...``), which counts as that many solves.
When a run starts, the workflow writes the scene's plan, ``results/{scene}/logs/plan.json``
(:func:`write_plan`: the number of planned solves and the cores Snakemake was given). From the
plan and the step lines so far, :func:`scene_progress` tells what is done and estimates what is
left: the solves still to do, at the mean pace of the solves done, spread over the cores. Each
contact job logs it when it ends, and ``python -m roughcontact.pipeline.progress results/SCENE`` prints it
at any time (from another terminal while a run goes on).
"""

from __future__ import annotations

import argparse
import json
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from ..core.cli import input_errors, read_json_object, require_folder
from ..core.files import write_text_atomic
from .io import duration_text
from .sources import source_of

#: The per-step line of a contact job's log (workflow/scripts/contact.py), or of a batch's (``B cases``).
STEP_LINE = re.compile(r"step (\d+)/(\d+): .*?, (?:(\d+) cases, )?\d+ iterations, ([0-9.]+) s")
#: The folders under ``results/{scene}/logs/`` of the jobs that solve contact cases.
SOLVE_LOGS = ("contact", "contact_batch")
PLAN_FILE = "plan.json"


def planned_solves(scene: Mapping) -> int:
    """Load steps the contact study of a validated scene solves: its source's cases x ``n_steps``; 0 without one."""
    if "contact" not in scene:
        return 0
    return len(source_of(scene).cases(scene, "contact")) * scene["contact"]["load"]["n_steps"]


def write_plan(scene_dir: str | Path, scene_name: str, scene: Mapping, cores: int) -> Path:
    """Write ``{scene_dir}/logs/plan.json``: the scene, its planned solves and the cores of this run."""
    plan = {"scene": scene_name, "solves": planned_solves(scene), "cores": max(1, int(cores or 1))}
    return write_text_atomic(Path(scene_dir) / "logs" / PLAN_FILE, json.dumps(plan, sort_keys=True) + "\n")


@dataclass(frozen=True)
class Progress:
    """A scene's contact study so far: solves planned and done, seconds spent on them, cores."""

    planned: int
    done: int
    seconds: float
    cores: int

    def left_seconds(self) -> float | None:
        """Estimated wall time left [s]: the solves to do at the mean pace so far over the cores; None before any."""
        if self.done == 0:
            return None
        return max(self.planned - self.done, 0) * (self.seconds / self.done) / self.cores

    def text(self, scene: str) -> str:
        """One line for a log or a terminal."""
        head = f"scene {scene!r}: {self.done} of {self.planned} contact solves done"
        left = self.left_seconds()
        if left is None:
            return head + "; no pace yet"
        if self.done >= self.planned:
            return head + " (all)"
        return (f"{head} ({100 * self.done / self.planned:.0f} %), {self.seconds / self.done:.3g} s a solve: "
                f"about {duration_text(left)} left on {self.cores} core(s)")


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
    plan = read_json_object(path, {"scene": str, "solves": int, "cores": int})
    if plan["solves"] < 0 or plan["cores"] < 1:
        raise ValueError(f"{path}: solves = {plan['solves']} and cores = {plan['cores']} must be >= 0 and >= 1; "
                         "the workflow rewrites this file when a run starts")
    return plan


def scene_progress(scene_dir: str | Path) -> tuple[str, Progress] | None:
    """The scene's name and :class:`Progress` from its plan and contact logs; None without a plan."""
    scene_dir = Path(scene_dir)
    plan_path = scene_dir / "logs" / PLAN_FILE
    if not plan_path.is_file():
        return None
    plan = read_plan(plan_path)
    done, seconds = 0, 0.0
    for log in sorted(log for folder in SOLVE_LOGS for log in (scene_dir / "logs" / folder).rglob("*.log")):
        for cases, step_seconds in read_log_solves(log.read_text(errors="replace")):
            done, seconds = done + cases, seconds + step_seconds
    return plan["scene"], Progress(plan["solves"], min(done, plan["solves"]), seconds, plan["cores"])


def main(argv=None) -> None:
    """``python -m roughcontact.pipeline.progress results/SCENE``: print how far the scene's contact study has got."""
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

"""The run's ETA against the time actually left (issue 62): ``python -m roughcontact.pipeline.progress`` sampled
while a scene runs, then compared with the truth once it has ended.

The scene runs under Snakemake in a throwaway copy of the workflow (``--cores`` as given); every ``--every``
seconds this script asks :func:`roughcontact.pipeline.progress.scene_progress` for the estimate, as the command
would. When the run has ended, the time left at each sample is known (its end minus the sample's time); the
table gives, at 20, 50 and 80 % of the run's wall time, the estimate, the truth and their ratio (the nearest
sample at or after that point). The goal: within a factor of 2 from 20 % onwards.

Run it with ``python benchmarks/bench_progress.py --scene demo [--batch 4] [--out FILE]``. ``--batch B`` sets
``contact.solver.batch: B`` on the scene (its contact cases solved B at a time): a batched scene.
"""

from __future__ import annotations

import argparse
import datetime
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from roughcontact.pipeline.progress import scene_progress  # noqa: E402

#: Where in the run's wall time the table compares the estimate with the truth.
POINTS = (0.2, 0.5, 0.8)


def copy_workflow(dest: Path, scene: str, batch: int | None) -> Path:
    """A copy of the workflow (Snakefile, rules, scripts, config, profiles, data, envs) with ``scene`` the default."""
    dest.mkdir(parents=True)
    for name in ("Snakefile", "workflow", "config", "profiles", "data", "envs"):
        src = REPO / name
        if src.is_dir():
            shutil.copytree(src, dest / name)
        elif src.is_file():
            shutil.copy(src, dest / name)
    config = yaml.safe_load((dest / "config" / "config.yaml").read_text())
    config["scene"] = scene
    if batch:  # a batch stores no fields: the scene's outputs.fields go
        contact = config["scenes"][scene].setdefault("contact", {})
        contact.setdefault("solver", {})["batch"] = batch
        contact.get("outputs", {}).pop("fields", None)
    (dest / "config" / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
    return dest


def sample_run(workdir: Path, scene: str, cores: int, every: float) -> tuple[float, float, list[tuple[float, float]]]:
    """Run the scene, sampling the estimate; ``(start, end, [(time, estimate left [s])])``."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "src"), os.environ.get("PYTHONPATH", "")])}
    snakemake = Path(sys.executable).parent / "snakemake"
    start = time.time()
    log = open(workdir / "run.log", "w")  # a file, not a pipe: an unread pipe fills and stops the run
    proc = subprocess.Popen([str(snakemake), f"-j{cores}"], cwd=workdir, env=env, stdout=log, stderr=log, text=True)
    samples = []
    while proc.poll() is None:
        time.sleep(every)
        cwd = os.getcwd()
        os.chdir(workdir)
        try:
            got = scene_progress(Path("results") / scene)
        except (OSError, ValueError):
            got = None
        finally:
            os.chdir(cwd)
        if got is not None and got[1].left is not None:
            samples.append((time.time(), got[1].left))
    end = time.time()  # the command has returned (to within one sampling interval): what a user waits for
    log.close()
    if proc.returncode != 0:
        raise SystemExit(f"the run failed:\n{(workdir / 'run.log').read_text()[-3000:]}")
    return start, end, samples


def table(start: float, end: float, samples: list[tuple[float, float]]) -> list[tuple[float, float, float, float]]:
    """``(fraction, estimate, truth, ratio)`` at each of :data:`POINTS`."""
    rows = []
    for point in POINTS:
        at = start + point * (end - start)
        later = [(t, left) for t, left in samples if t >= at and t < end]
        if not later:
            continue
        t, left = later[0]
        truth = end - t
        rows.append(((t - start) / (end - start), left, truth, left / truth if truth > 0 else float("inf")))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="demo")
    ap.add_argument("--batch", type=int, default=None, help="contact.solver.batch for the scene")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--every", type=float, default=1.0, help="seconds between samples")
    ap.add_argument("--out", type=Path, help="append the table (Markdown) to this file")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-progress-") as tmp:
        wd = copy_workflow(Path(tmp) / "wf", args.scene, args.batch)
        start, end, samples = sample_run(wd, args.scene, args.cores, args.every)
    rows = table(start, end, samples)
    load = os.getloadavg()
    when = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    label = args.scene + (f", contact.solver.batch {args.batch}" if args.batch else "")
    lines = [f"\n{when}, scene {label}, -j{args.cores}, run {end - start:.0f} s, load average "
             f"{load[0]:.1f} {load[1]:.1f} {load[2]:.1f}, {len(samples)} samples\n",
             "| at | estimate left | truth left | estimate / truth |", "|---|---|---|---|"]
    lines += [f"| {100 * f:.0f} % | {e:.1f} s | {t:.1f} s | {r:.2f} |" for f, e, t, r in rows]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        with open(args.out, "a", encoding="utf-8") as fh:
            fh.write(text)


if __name__ == "__main__":
    main()

#!/usr/bin/env python
"""What Snakemake and Python start-up cost on the representativity study, against its work.

Runs the representativity part of a scene (default ``paper``: 900 surfaces at N = 1024, the
paper's grid) through Snakemake in a fresh copy of the workflow, with ``--cores`` (default 2)
and single-threaded numerical libraries, and reads back:

- each job's **work**: the CPU and wall time of computing its surfaces, their eps and writing its
  file, from the ``computed ... in X s CPU, Y s wall`` line of the job's log;
- each job's **whole CPU**: the exact figure its log ends with (``getrusage``, read by
  :func:`roughcontact.pipeline.runcost.read_job`; Snakemake's own ``cpu_time`` samples a job every 30 s after
  its first 15 s and can miss up to 30 s of it, snakemake/snakemake#851);
- **start-up CPU**, measured directly: fresh interpreters that import what a representativity
  job imports (Snakemake's script preamble, ``roughcontact.pipeline.datasets``, ``roughcontact.pipeline.io``);
- the **whole part**: wall time and CPU (``getrusage`` of the ``snakemake`` call and all its
  children: planning, every job, the aggregate).

It reports the overhead as ``(whole CPU - sum(work CPU)) / sum(work CPU)`` (everything that is not
the surfaces' work: Snakemake, start-ups, the aggregate) and as ``jobs x start-up / sum(work CPU)``
(issue 13 asks < 10 %), and the wall-time efficiency ``sum(work wall) / (cores x whole wall)``.

Usage::

    python benchmarks/bench_representativity.py                   # paper scene, 2 cores
    python benchmarks/bench_representativity.py --scene demo --cores 2 --out benchmarks/out/rep.md
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from roughcontact.pipeline.runcost import read_job

REPO = Path(__file__).resolve().parents[1]
WORK_LINE = re.compile(r"computed (\d+) surfaces in ([0-9.]+) s CPU, ([0-9.]+) s wall")


def copy_workflow(dest: Path) -> Path:
    """A throwaway copy of the workflow (Snakefile, workflow/, config/, envs/, data/)."""
    shutil.copy(REPO / "Snakefile", dest / "Snakefile")
    for name in ("workflow", "config", "envs", "data"):
        shutil.copytree(REPO / name, dest / name)
    return dest


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def startup_cpu(repeats: int = 5) -> float:
    """CPU [s] of a fresh interpreter importing what a representativity job imports (best of ``repeats``)."""
    code = "import snakemake.script, roughcontact.pipeline.datasets, roughcontact.pipeline.io"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO / "src"),
                                                                      os.environ.get("PYTHONPATH")]))}
    best = float("inf")
    for _ in range(repeats):
        before = _children_cpu()
        subprocess.run([sys.executable, "-c", code], check=True, env=env)
        best = min(best, _children_cpu() - before)
    return best


def run_part(workdir: Path, scene: str, cores: int) -> tuple[float, float]:
    """Run the scene's representativity aggregate with Snakemake; its wall time and CPU [s]."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO / "src"), os.environ.get("PYTHONPATH")]))}
    snakemake = Path(sys.executable).with_name("snakemake")
    cmd = [str(snakemake), "-j", str(cores), "--scheduler", "greedy", "--config", f"scene={scene}",
           "--", f"results/{scene}/aggregate/representativity.nc"]
    start, cpu = time.perf_counter(), _children_cpu()
    res = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - start, _children_cpu() - cpu
    if res.returncode != 0:
        sys.exit(f"snakemake failed ({res.returncode}):\n{res.stderr[-4000:]}")
    return wall, cpu


def job_times(workdir: Path, scene: str) -> list[dict]:
    """Per representativity job: surfaces, work CPU and wall, whole CPU (its log), whole wall (its benchmark)."""
    rows = []
    for log in sorted((workdir / "results" / scene / "logs" / "representativity").glob("*.log")):
        match = WORK_LINE.search(log.read_text())
        if match is None:
            sys.exit(f"{log}: no 'computed ... surfaces in ... s CPU' line")
        row = read_job(workdir / "results" / scene / "benchmarks" / "representativity" / (log.stem + ".tsv"))
        rows.append({"job": log.stem, "surfaces": int(match[1]), "work_cpu": float(match[2]),
                     "work_wall": float(match[3]), "job_cpu": float(row["cpu_time"]), "job_wall": float(row["s"])})
    return rows


def load() -> str:
    one, five, _ = os.getloadavg()
    return f"{one:.2f} (1 min), {five:.2f} (5 min)"


def report(rows: list[dict], wall: float, cpu: float, startup: float, cores: int, scene: str,
           load_before: str) -> str:
    work_cpu = sum(r["work_cpu"] for r in rows)
    job_cpu = sum(r["job_cpu"] for r in rows)
    work_wall = sum(r["work_wall"] for r in rows)
    n = len(rows)
    lines = [
        f"# Representativity part of scene `{scene}` on {cores} cores "
        f"({dt.datetime.now(dt.UTC):%Y-%m-%d %H:%M} UTC)",
        "",
        f"Load before: {load_before}; after: {load()}. Python {sys.version.split()[0]}, {os.cpu_count()} CPUs.",
        "",
        "| job | surfaces | work CPU [s] | job CPU, its log [s] | work wall [s] | job wall [s] |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    lines += [f"| {r['job']} | {r['surfaces']} | {r['work_cpu']:.2f} | {r['job_cpu']:.2f} | "
              f"{r['work_wall']:.2f} | {r['job_wall']:.2f} |" for r in rows]
    lines += [
        "",
        f"- jobs: {n}, surfaces: {sum(r['surfaces'] for r in rows)}; work {work_cpu:.1f} s CPU "
        f"(the whole jobs, their logs: {job_cpu:.1f} s CPU)",
        f"- start-up of one job, measured directly: {startup:.2f} s CPU; **{n} start-ups = "
        f"{100 * n * startup / work_cpu:.1f} % of the work**",
        f"- whole part (`snakemake` call: planning, jobs, aggregate): **{wall:.1f} s wall, {cpu:.1f} s CPU**; "
        f"**everything but the work: {100 * (cpu - work_cpu) / work_cpu:.1f} % of the work**; "
        f"wall efficiency sum(work wall) / ({cores} x wall) = {work_wall / (cores * wall):.2f}",
    ]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="paper")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--out", type=Path, help="also write the report here (markdown)")
    ap.add_argument("--keep", action="store_true", help="keep the workflow copy and say where")
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="bench-rep-"))
    try:
        workdir = copy_workflow(tmp)
        load_before = load()
        startup = startup_cpu()
        wall, cpu = run_part(workdir, args.scene, args.cores)
        text = report(job_times(workdir, args.scene), wall, cpu, startup, args.cores, args.scene, load_before)
    finally:
        if args.keep:
            print(f"workflow copy kept in {tmp}", file=sys.stderr)
        else:
            shutil.rmtree(tmp, ignore_errors=True)
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)


if __name__ == "__main__":
    main()

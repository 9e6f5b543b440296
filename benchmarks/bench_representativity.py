#!/usr/bin/env python
"""What Snakemake and Python start-up cost on the representativity study, against its work.

Runs the representativity part of a scene (default ``paper``: 900 surfaces at N = 1024, the
paper's grid) through Snakemake in a fresh copy of the workflow, with ``--cores`` (default 2)
and single-threaded numerical libraries, and reads back:

- each job's **work**: the CPU and wall time of computing its surfaces, their eps and writing its
  file, from the ``computed ... in X s CPU, Y s wall`` line of the job's log;
- each job's **whole CPU**: Snakemake's benchmark file (``cpu_time``: the job's process tree,
  from interpreter start to exit);
- the **wall time of the whole part**: the ``snakemake`` call, planning and aggregate included.

It reports the start-up overhead ``sum(job CPU) / sum(work CPU) - 1`` (issue 13 asks < 10 %), the
start-up CPU per job, and the wall-time efficiency ``sum(work wall) / (cores x whole wall)``.

Usage::

    python benchmarks/bench_representativity.py                   # paper scene, 2 cores
    python benchmarks/bench_representativity.py --scene demo --cores 2 --out benchmarks/out/rep.md
"""

from __future__ import annotations

import argparse
import csv
import datetime as dt
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
WORK_LINE = re.compile(r"computed (\d+) surfaces in ([0-9.]+) s CPU, ([0-9.]+) s wall")


def copy_workflow(dest: Path) -> Path:
    """A throwaway copy of the workflow (Snakefile, workflow/, config/, envs/, data/)."""
    shutil.copy(REPO / "Snakefile", dest / "Snakefile")
    for name in ("workflow", "config", "envs", "data"):
        shutil.copytree(REPO / name, dest / name)
    return dest


def run_part(workdir: Path, scene: str, cores: int) -> float:
    """Run the scene's representativity aggregate with Snakemake; its wall time [s]."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO / "src"), os.environ.get("PYTHONPATH")]))}
    snakemake = Path(sys.executable).with_name("snakemake")
    cmd = [str(snakemake), "-j", str(cores), "--scheduler", "greedy", "--config", f"scene={scene}",
           "--", f"results/{scene}/aggregate/representativity.nc"]
    start = time.perf_counter()
    res = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if res.returncode != 0:
        sys.exit(f"snakemake failed ({res.returncode}):\n{res.stderr[-4000:]}")
    return wall


def job_times(workdir: Path, scene: str) -> list[dict]:
    """Per representativity job: surfaces, work CPU and wall (its log), whole CPU and wall (its benchmark)."""
    rows = []
    for log in sorted((workdir / "results" / scene / "logs" / "representativity").glob("*.log")):
        match = WORK_LINE.search(log.read_text())
        if match is None:
            sys.exit(f"{log}: no 'computed ... surfaces in ... s CPU' line")
        bench = workdir / "results" / scene / "benchmarks" / "representativity" / (log.stem + ".tsv")
        with open(bench) as fh:
            row = next(csv.DictReader(fh, delimiter="\t"))
        rows.append({"job": log.stem, "surfaces": int(match[1]), "work_cpu": float(match[2]),
                     "work_wall": float(match[3]), "job_cpu": float(row["cpu_time"]), "job_wall": float(row["s"])})
    return rows


def load() -> str:
    one, five, _ = os.getloadavg()
    return f"{one:.2f} (1 min), {five:.2f} (5 min)"


def report(rows: list[dict], wall: float, cores: int, scene: str, load_before: str) -> str:
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
        "| job | surfaces | work CPU [s] | job CPU [s] | start-up CPU [s] | work wall [s] | job wall [s] |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    lines += [f"| {r['job']} | {r['surfaces']} | {r['work_cpu']:.2f} | {r['job_cpu']:.2f} | "
              f"{r['job_cpu'] - r['work_cpu']:.2f} | {r['work_wall']:.2f} | {r['job_wall']:.2f} |" for r in rows]
    lines += [
        "",
        f"- jobs: {n}, surfaces: {sum(r['surfaces'] for r in rows)}",
        f"- work: {work_cpu:.1f} s CPU; whole jobs: {job_cpu:.1f} s CPU; start-up "
        f"{(job_cpu - work_cpu) / n:.2f} s CPU a job",
        f"- **start-up overhead: {100 * (job_cpu / work_cpu - 1):.1f} % of the work** (CPU)",
        f"- whole part (`snakemake` call, planning and aggregate included): **{wall:.1f} s wall**; "
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
        wall = run_part(workdir, args.scene, args.cores)
        text = report(job_times(workdir, args.scene), wall, args.cores, args.scene, load_before)
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

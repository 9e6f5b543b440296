"""Every example file of SurfaceTopography's test suite through :func:`read_topography`, one line each.

SurfaceTopography's repository keeps example files of every format it reads in
``test/file_format_examples`` (https://github.com/ContactEngineering/SurfaceTopography, MIT
licence; some are Git LFS objects that a plain copy may lack). This sweep reads each file of such a
folder as a measured scene would (heights in um, best plane removed, undefined points filled
harmonically; ``file_unit`` um and a 10 x 10 um size for files that carry neither) and says what
happened:

- ``read``: the heights the solver would get (shape, sides, undefined fraction);
- ``refused``: a :class:`~roughcontact.surfaces.topography.TopographyError`, the clear message a
  user gets (line scans, maps under 4 x 4, unknown or damaged files, ...);
- ``CRASH``: any other exception, a traceback from deep inside a library: a bug of ours.

The exit status is 1 when a file crashed. ``--scene FILE`` also writes a scene (YAML, for
``snakemake --configfile FILE``) with every read file, to take them all through every stage.
``--solve`` then solves each read file directly, as the measured scene does but at the hard-case
suite's resolution of the load: 30 steps to ``p0 / (E* h') = --p-max`` (default 0.05, the measured
scenes' default), free boundary, tol 1e-8, one thread; a line per file with the steps converged,
iterations, the paths that ended the steps, CPU and the last A/A0 (the exit status is 1 also when
a step did not converge). ``--hardness H`` adds a plasticity cap ``H E* h'`` (the capped iteration);
``--peer NODES`` compares A/A0 at the last load with ContactMechanics' (test-only peer) on maps of
at most ``NODES`` points::

    python benchmarks/formats/sweep.py --from DIR [--scene sweep.yaml] [--skip NAME ...] \
        [--solve [--hardness H] [--peer NODES]]
"""

from __future__ import annotations

import argparse
import collections
import functools
import os
import re
import sys
import time
import traceback
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import yaml

from roughcontact.surfaces.topography import TopographyError, read_topography

READ_OPTIONS = {"unit": "um", "file_unit": "um", "physical_size": (10.0, 10.0), "undefined": "harmonic",
                "detrend": "height"}


def read_one(path: Path) -> tuple[str, str]:
    """``(outcome, detail)`` of reading ``path`` with :data:`READ_OPTIONS`: outcome read, refused or CRASH."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            surface = read_topography(path, **READ_OPTIONS)
    except TopographyError as err:
        return "refused", str(err).removeprefix(f"{path}: ")
    except Exception as err:  # what the sweep is for: anything but a TopographyError is a bug
        frame = traceback.extract_tb(err.__traceback__)[-1]
        return "CRASH", f"{type(err).__name__}: {err} (at {Path(frame.filename).name}:{frame.lineno})"
    undefined = surface.info.get("undefined_fraction", 0.0)
    if surface.dimension == 1:  # a line scan, read as a profile (issue 49); a non-uniform one resampled
        how = "non-uniform, resampled" if "resampled" in surface.info else "uniform"
        return "read", (f"profile of {surface.heights.size} points ({how}), {surface.length:.4g} um, "
                        f"{100 * undefined:.1f} % undefined, {surface.info['format']}")
    nx, ny = surface.heights.shape
    lx, ly = np.broadcast_to(surface.lengths, 2)
    return "read", f"{nx} x {ny}, {lx:.4g} x {ly:.4g} um, {100 * undefined:.1f} % undefined, {surface.info['format']}"


def sweep(folder: Path, skip: tuple[str, ...] = ()) -> list[tuple[str, str, str]]:
    """``(file name, outcome, detail)`` for every file in ``folder`` (sorted), less the names in ``skip``."""
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.name not in skip)
    return [(p.name, *read_one(p)) for p in files]


def case_name(file_name: str) -> str:
    """A case name for a file: its stem in lower case, other characters than [a-z0-9-] as '-'."""
    return re.sub(r"[^a-z0-9-]", "-", Path(file_name).stem.lower().replace("_", "-"))


def scene(folder: Path, rows: list[tuple[str, str, str]]) -> dict:
    """A measured scene (the test-suite's loads: 4 steps to p0/(E* h') = 0.02) with every read map (line scans,
    read as profiles, cannot share a scene with maps)."""
    files = {case_name(name): {"path": str(folder.resolve() / name), "file_unit": "um",
                               "physical_size": [10.0, 10.0]}
             for name, outcome, detail in rows if outcome == "read" and not detail.startswith("profile")}
    return {"scene": "formats", "scenes": {"formats": {
        "description": "Every example file of SurfaceTopography's test suite that reads, through every stage.",
        "topography": {"files": files, "unit": "um", "undefined": "harmonic", "detrend": "height"},
        "representativity": {"n_bins": 50},
        "contact": {"load": {"relative_to": "rms_slope", "p_max": 0.02, "n_steps": 4},
                    "solver": {"e_star": 1.0e5, "pressure_unit": "MPa"}},
    }}}


def solve_one(path: Path, p_max: float, steps: int = 30, hardness: float | None = None,
              peer: bool = False) -> tuple[bool, str]:
    """``(all converged, line)``: ``path`` solved over ``steps`` loads to ``p0 / (E* h') = p_max`` (E* = 1),
    with a plasticity cap ``H = hardness E* h'`` where given (the line then ends with the plastic area).

    ``peer``: the last load solved again, from scratch, by ContactMechanics' free-boundary CG
    (:func:`peer_area`); the line ends with its A/A0 and ``|A_ours - A_peer| / A_peer``.
    """
    from roughcontact.solver import solve_contact
    from roughcontact.solver.workspace import SOLVER_PATHS
    from roughcontact.surfaces.synthetic import nonperiodic_moments

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        surface = read_topography(path, **READ_OPTIONS)
    slope = nonperiodic_moments(surface.heights, surface.length)["rms_slope"]
    loads = [p_max * slope * (k + 1) / steps for k in range(steps)]
    cpu = time.process_time()
    cap = {} if hardness is None else {"hardness": hardness * slope}
    ds = solve_contact(surface.heights, loads, e_star=1.0, length=surface.length, tol=1e-8, boundary="free", **cap)
    cpu = time.process_time() - cpu
    converged = int(ds["converged"].sum())
    paths = dict(collections.Counter(SOLVER_PATHS[x] for x in ds["solver_path"].values))
    return converged == steps, (f"| {path.name} | {' x '.join(str(n) for n in surface.heights.shape)} | "
                                f"{converged}/{steps} | {int(ds['iterations'].sum())} | "
                                f"{', '.join(f'{k} {v}' for k, v in sorted(paths.items()))} | {cpu:.1f} | "
                                f"{float(ds['area_fraction'][-1]):.4f} |"
                                + (f" {float(ds['plastic_area_fraction'][-1]):.4f} |" if cap else "")
                                + (_peer_cells(surface, loads[-1], float(ds["area_fraction"][-1])) if peer else ""))


def _peer_cells(surface, p0: float, ours: float) -> str:
    """`` A_peer | rel. difference | peer iterations |`` at mean pressure ``p0`` (E* = 1), or why not."""
    area, nit, success = peer_area(surface.heights, surface.length, 1.0, p0, 1e-8, 10_000)
    if not success:
        return f" not converged in {nit} | - | {nit} |"
    return f" {area:.4f} | {abs(ours - area) / area:.1e} | {nit} |"


def peer_area(h, length, e_star: float, p0: float, tol: float, maxiter: int):
    """ContactMechanics' A/A0, iterations and success: the hard-case table's peer (``benchmarks/hardcases``)."""
    return _hardcases_table().peer_area(h, length, e_star, p0, tol, maxiter)


@functools.cache
def _hardcases_table():
    """``benchmarks/hardcases/table.py`` as a module (a script, not a package), loaded once."""
    import importlib.util

    script = Path(__file__).resolve().parents[1] / "hardcases" / "table.py"
    spec = importlib.util.spec_from_file_location("hardcases_table", script)
    table = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(table)
    return table


def table(rows: list[tuple[str, str, str]]) -> str:
    """The rows as a markdown table, with a count of each outcome first."""
    counts = {o: sum(r[1] == o for r in rows) for o in ("read", "refused", "CRASH")}
    lines = [", ".join(f"{n} {o}" for o, n in counts.items()), "", "| file | outcome | detail |", "|---|---|---|"]
    lines += [f"| {name} | {outcome} | {detail.replace('|', '/')} |" for name, outcome, detail in rows]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--from", dest="folder", type=Path, required=True,
                    help="a copy of SurfaceTopography's test/file_format_examples")
    ap.add_argument("--scene", type=Path, help="write a scene with every read file to this YAML file")
    ap.add_argument("--skip", nargs="*", default=(), help="file names to leave out")
    ap.add_argument("--solve", action="store_true", help="then solve every read file (30 steps, free boundary)")
    ap.add_argument("--p-max", type=float, default=0.05, help="--solve's last load p0 / (E* h') (default 0.05)")
    ap.add_argument("--hardness", type=float, help="--solve with a plasticity cap H / (E* h') (above --p-max)")
    ap.add_argument("--peer", type=int, metavar="NODES", default=0,
                    help="--solve: ContactMechanics' A/A0 at the last load for maps of at most NODES points")
    args = ap.parse_args(argv)
    if not args.folder.is_dir():
        ap.error(f"--from {args.folder}: not a folder")
    rows = sweep(args.folder, tuple(args.skip))
    print(table(rows))
    if args.scene:
        args.scene.write_text(yaml.safe_dump(scene(args.folder, rows), sort_keys=False))
    failed = any(outcome == "CRASH" for _, outcome, _ in rows)
    if args.solve:
        extra = [] if args.hardness is None else [f"plastic area (H/(E* h') = {args.hardness:g})"]
        extra += ["A/A0 ContactMechanics", "rel. difference", "its. ContactMechanics"] if args.peer else []
        print(f"\n| file | grid | converged | iterations | paths (steps) | CPU [s] | A/A0 at p0/(E* h') = "
              f"{args.p_max:g} |{''.join(f' {e} |' for e in extra)}\n|{'---|' * (7 + len(extra))}", flush=True)
        for name, outcome, detail in rows:
            if outcome == "read":
                grid = re.match(r"(\d+) x (\d+),", detail) or re.match(r"profile of (\d+) points", detail)
                nodes = np.prod([int(n) for n in grid.groups()])  # read_one's detail: nx x ny, or a profile's n
                ok, line = solve_one(args.folder / name, args.p_max, hardness=args.hardness,
                                     peer=args.peer > 0 and nodes <= args.peer)
                line += " - | - | - |" if args.peer > 0 and nodes > args.peer else ""
                failed |= not ok
                print(line, flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

"""Prove that a refactoring left the pipeline's outputs unchanged: run the scene families with one commit's code,
then compare two such runs file by file.

Usage::

    python benchmarks/same_outputs.py run --repo /path/to/checkout --out DIR [--families demo lines ...]
    python benchmarks/same_outputs.py compare DIR_A DIR_B [--families ...]

``run`` copies the workflow of the checkout ``--repo`` (as ``tests/conftest.py``'s ``copy_workflow`` does) into
``DIR/<family>/wd``, writes the family's config there and runs ``snakemake -j2 --config scene=<scene>`` with
``PYTHONPATH=<repo>/src``, so that the code of ``--repo`` runs. The configs are this checkout's tests' own
(``conftest.FAMILIES`` and the two below): both sides of a comparison get the same inputs; a family whose config is
None (``demo``) runs the shipped config of ``--repo`` as it is.

``compare`` compares every ``*.nc`` and ``*.csv`` under each family's ``results/`` byte by byte. Two runs of one commit
on one machine write the same bytes (tests/test_workflow.py's rerun; measured with this tool on f89aa95: two runs of
``adhesion``, ``ranks2``, ``batched`` and ``measured``, every file identical, no variable or attribute that changes from
run to run: the solver's ``wall_time`` is not written), so nothing is excluded. The files of ``ranks2`` and any file
that differs are also opened with xarray (every group) and the largest relative difference of each variable reported;
``ranks2`` passes within :data:`MPI_RTOL`. The exit status is 0 only when every other file is byte-identical.

Across the one contact path (issue 64, 2026-12-02) a run of the older layout (the f89aa95 baseline) is compared as
:func:`older_layout` says: a batch's file and an MPI job's file moved to ``contact/`` under the same name, and the
per-case copies the older layout made of them are gone, each case now written once (its group of a batch's file, or
the MPI job's own file, which stands for its copy). Each copy of a batch's case is checked to hold its group's
variables and attributes exactly (xarray's ``identical``), since a copy was written again from what it read (its
bytes are not the original's).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]  # this checkout: its tests' configs and helpers
sys.path.insert(0, str(ROOT / "tests"))
from conftest import FAMILIES, TINY, copy_workflow, edited_contact, run_snakemake  # noqa: E402

#: The agreement of the MPI solve with the single solve asked by the tests: the mean gap to ``rtol=1e-6``
#: (tests/test_solver_mpi.py, test_same_answers_as_the_single_solve; tests/test_pipeline_mpi.py,
#: test_ranks_2_equals_the_run_in_one_process), the strictest of their tolerances (A/A0 to 2 nodes, kappa and the
#: stiffness to 1e-4, the perimeter to 1e-3). Here applied to every variable, relative to its largest magnitude.
MPI_RTOL = 1e-6

#: The families run by default: the tests' (conftest.FAMILIES, under short names), then two of this tool's own.
NAMES = {"demo": "paper-like", "lines": "profiles", "adhesion": "adhesion", "measured": "measured", "array": "array"}
#: The tiny scene in batches of 2 (tests/test_pipeline_batch.py's BATCHED has 5 seeds in batches of 4: a full and
#: a short batch; here 3 seeds in batches of 2) and over 2 MPI ranks (tests/test_pipeline_mpi.py's SPLIT).
EXTRA = {"batched": lambda: edited_contact(TINY, **{"seeds": 3, "solver.batch": 2}),
         "ranks2": lambda: edited_contact(TINY, **{"solver.ranks": 2})}
ALL = [*NAMES, *EXTRA]


def family_config(name: str) -> tuple[str, dict | None, dict]:
    """Family ``name``'s scene, config (None: the shipped one) and files to copy (``{destination: source}``)."""
    if name in EXTRA:
        return "tiny", EXTRA[name](), {}
    family = FAMILIES[NAMES[name]]
    return family.scene, family.config(), dict(family.files)


def run(repo: Path, out: Path, families: list[str]) -> None:
    """Run each family with the code of ``repo`` in ``out/<family>/wd``; stop at the first failing run."""
    env = {**os.environ, "PYTHONPATH": str(repo / "src")}
    found = subprocess.run([sys.executable, "-c", "import roughcontact; print(roughcontact.__file__)"], env=env,
                           capture_output=True, text=True, check=True).stdout.strip()
    if not Path(found).is_relative_to(repo / "src"):
        sys.exit(f"with PYTHONPATH={repo / 'src'} roughcontact is imported from {found}, not from --repo")
    for name in families:
        wd = out / name / "wd"
        if wd.exists():
            sys.exit(f"{wd} exists: remove it or choose another --out")
        scene, config, files = family_config(name)
        copy_workflow(wd, config, source=repo)
        for dest, source in files.items():
            (wd / dest).write_bytes(Path(source).read_bytes())
        start = time.monotonic()
        res = run_snakemake(wd, "-j2", "--config", f"scene={scene}", env=env)
        wall = time.monotonic() - start
        (out / name / "snakemake.log").write_text(res.stdout + res.stderr)
        if res.returncode != 0:
            sys.exit(f"{name}: snakemake failed (exit {res.returncode}) after {wall:.0f} s; "
                     f"{out / name / 'snakemake.log'}:\n{res.stderr[-3000:]}")
        print(f"{name} ({scene}): {wall:.0f} s, {len(result_files(wd / 'results'))} files", flush=True)


def result_files(root: Path) -> set[Path]:
    """The ``*.nc`` and ``*.csv`` files under ``root``, relative to it."""
    return {p.relative_to(root) for p in root.rglob("*") if p.suffix in (".nc", ".csv") and p.is_file()}


def columns(path: Path) -> dict[str, np.ndarray]:
    """Every variable of every group of a NetCDF file (``group/name``; a group's attributes as ``group/:attrs``),
    or every column of a CSV file."""
    if path.suffix == ".csv":
        table = pd.read_csv(path)
        return {name: table[name].to_numpy() for name in table.columns}
    out = {}
    with xr.open_datatree(path) as tree:
        for node in tree.subtree:
            group = node.path.strip("/")
            out[f"{group}/:attrs".lstrip("/")] = np.array(repr(sorted(node.attrs.items())))
            out.update({f"{group}/{name}".lstrip("/"): var.values for name, var in node.dataset.variables.items()})
    return out


def largest_differences(a: Path, b: Path) -> dict[str, float]:
    """Per variable (column) of two NetCDF (CSV) files: max |a - b| / max |b|; inf where the shapes differ or a
    variable is in one file only, and where non-numbers (attributes, labels) differ."""
    ca, cb = columns(a), columns(b)
    out = {}
    for key in ca.keys() | cb.keys():
        x, y = ca.get(key), cb.get(key)
        if x is None or y is None or x.shape != y.shape:
            out[key] = float("inf")
        elif np.issubdtype(y.dtype, np.number) and np.issubdtype(x.dtype, np.number):
            x, y = x.astype(float), y.astype(float)
            diff = np.max(np.abs(x - y), initial=0.0, where=~(np.isnan(x) & np.isnan(y)))
            scale = np.max(np.abs(y), initial=0.0, where=~np.isnan(y))
            out[key] = float(diff / scale) if scale > 0 else (0.0 if diff == 0 else float("inf"))
        else:
            out[key] = 0.0 if np.array_equal(x, y) else float("inf")
    return out


#: Folders of the older layout whose files moved to ``contact/`` under the same name (issue 64, item 2).
MOVED_TO_CONTACT = ("contact_batch", "contact_mpi")


def older_layout(root: Path, files: set[Path], other: set[Path]) -> tuple[dict[Path, Path], dict[Path, Path]]:
    """A run of the layout before the one contact path, as the newer one names its files.

    Returns ``(files, copies)``: every file of ``root`` by its newer name (``<scene>/contact_batch/X`` and
    ``<scene>/contact_mpi/X`` become ``<scene>/contact/X``, replacing the copy of the same name), and the older
    per-case copies of a batch's cases that the newer layout (``other``) no longer has, each with what it copied
    (``file`` or ``file#group``, relative to ``root``). A run of the newer layout comes back unchanged, with no copies.
    """
    named = {p: p for p in files}
    for p in sorted(files):
        if len(p.parts) == 3 and p.parts[1] in MOVED_TO_CONTACT:
            named[Path(p.parts[0], "contact", p.name)] = p
            del named[p]
    copies = {}
    for new, old in list(named.items()):
        if new.parts[1:2] != ("contact",) or new in other or old != new:
            continue
        batch = next((b for b in files if b.parts[1] == "contact_batch" and _holds_group(root / b, new.stem)), None)
        if batch is not None:
            copies[new] = Path(f"{batch}#{new.stem}")
            del named[new]
    return named, copies


def _holds_group(path: Path, group: str) -> bool:
    with xr.open_datatree(path) as tree:
        return group in tree.children


def _same_as_group(copy: Path, source: Path) -> bool:
    """Whether a per-case copy holds exactly the variables and attributes of its group in a batch's file."""
    path, group = str(source).split("#")
    with xr.open_dataset(path, group=group) as a, xr.open_dataset(copy) as b:
        a, b = a.load(), b.load()
    return a.identical(b) and a.attrs == b.attrs


def compare(dir_a: Path, dir_b: Path, families: list[str] | None = None) -> bool:
    """Print one line per family (files, identical, differing) and the differences; True when all pass.

    ``families``: those compared (None: every family run in either folder)."""
    ok = True
    found = {p.name for d in (dir_a, dir_b) for p in d.iterdir() if (p / "wd").is_dir()}
    for name in families or sorted(found):
        ra, rb = dir_a / name / "wd" / "results", dir_b / name / "wd" / "results"
        fa, fb = result_files(ra) if ra.is_dir() else set(), result_files(rb) if rb.is_dir() else set()
        na, copies_a = older_layout(ra, fa, fb)  # newer name -> file of dir_a
        nb, copies_b = older_layout(rb, fb, fa)
        fa, fb = set(na), set(nb)
        missing = sorted(fa ^ fb)
        differ = sorted(p for p in fa & fb if (ra / na[p]).read_bytes() != (rb / nb[p]).read_bytes())
        moved = [f"\n  moved: {na[p]} -> {nb[p]}" for p in sorted(fa & fb) if na[p] != nb[p]]
        copies = {(root / p, root / src) for root, got in ((ra, copies_a), (rb, copies_b)) for p, src in got.items()}
        bad_copies = sorted(str(c) for c, src in copies if not _same_as_group(c, src))
        print(f"{name}: {len(fa | fb)} files, {len(fa & fb) - len(differ)} identical, {len(differ)} differing"
              + "".join(moved)
              + (f"\n  {len(copies)} per-case copies of the older layout, each equal to its group: "
                 f"{'yes' if not bad_copies else 'NO: ' + ', '.join(bad_copies)}" if copies else "")
              + "".join(f"\n  differs: {p}" for p in differ)
              + "".join(f"\n  only in {dir_a if p in fa else dir_b}: {p}" for p in missing if fa and fb)
              + "".join(f"\n  no results in {d}" for d, files in ((dir_a, fa), (dir_b, fb)) if not files))
        family_ok = not missing and not differ and not bad_copies and bool(fa | fb)
        worst = {}
        for p in sorted(fa & fb) if name == "ranks2" else differ:
            for var, rel in largest_differences(ra / na[p], rb / nb[p]).items():
                worst[var] = max(worst.get(var, 0.0), rel)
        for var, rel in sorted(worst.items()):
            if rel > 0:
                print(f"  {var}: largest relative difference {rel:.3g}")
        if name == "ranks2" and fa and not missing:
            family_ok = all(rel <= MPI_RTOL for rel in worst.values())
            print(f"  ranks2 within rtol {MPI_RTOL:g} (the MPI solve's tolerance): {'yes' if family_ok else 'NO'}")
        ok &= family_ok
    return ok


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run the families with the code of --repo")
    r.add_argument("--repo", type=Path, required=True, help="the checkout whose workflow and src/ run")
    r.add_argument("--out", type=Path, required=True, help="folder of the runs (DIR/<family>/wd)")
    r.add_argument("--families", nargs="+", choices=ALL, default=ALL, metavar="FAMILY",
                   help=f"families to run (default: all of {' '.join(ALL)})")
    c = sub.add_parser("compare", help="compare two run folders file by file")
    c.add_argument("dirs", type=Path, nargs=2, metavar="DIR")
    c.add_argument("--families", nargs="+", choices=ALL, metavar="FAMILY",
                   help="families to compare (default: every family run in either folder)")
    args = parser.parse_args(argv)
    if args.command == "run":
        run(args.repo.resolve(), args.out.resolve(), args.families)
        return 0
    return 0 if compare(*args.dirs, args.families) else 1


if __name__ == "__main__":
    sys.exit(main())

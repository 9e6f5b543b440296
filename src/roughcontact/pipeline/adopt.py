"""Reuse the contact cases another run already computed with the same parameters.

    python -m roughcontact.pipeline.adopt results/reproduction --scene paper [--dry-run] [--configfile FILE ...]

Run from the workflow's folder. The config is read as Snakemake reads it: ``config/config.yaml``
with each ``--configfile`` added over it (mappings merged key by key), so a scene kept in its own
file is adopted into with ``--configfile my_scene.yaml --scene mine``, as it is run.

A contact case's file depends on its case ``(k_l, k_s, H, seed)``, the surface block and
the contact settings (all recorded in the file: case coordinates and the
``scene_parameters`` attribute) and on the code. Scenes whose grids overlap (the paper's
1200-case grid holds the reproduction's 360 cases) would solve those cases twice. For
each contact case the target scene plans and has no file for yet, this copies the source
run's file of the same case when

* it is a contact file of this package version holding exactly that case;
* its recorded parameters equal, as JSON, those the target's job would record;
* every case that both runs have computed is the same in both, in every variable and
  every attribute but ``scene``: the check that the two runs' code gives the same
  numbers, which neither the package version nor Snakemake can make. Without a case in
  common it refuses unless told ``trust_code``.

The copy differs from the source in its global attributes only: ``scene`` becomes the
target's (in its place, so that the aggregate's bytes do not depend on which of its
cases were adopted) and ``adopted_from`` names the source file. It is written
atomically, and listed in ``results/{scene}/adopted.tsv`` (case file, source file and
the sha256 of each). Snakemake then finds the output present and plans neither the job
nor its surface (temporary or kept); a scene whose contact map reads its cases' surfaces
(``outputs.fields``) is refused, as those surfaces would be made again and the cases re-solved. The
target's ``benchmarks/`` gets no file for an adopted case: :mod:`roughcontact.pipeline.runcost` reports its
cost in the source run on a row of its own.

Refuses while a Snakemake run holds the working directory: the jobs that run had
planned would overwrite the copies.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import shutil
from dataclasses import dataclass
from pathlib import Path

import netCDF4
import numpy as np

from ..core.cli import input_errors
from ..core.files import atomic_output, check_writable, file_sha256, write_text_atomic
from ..core.values import same_value
from ..core.version import __version__
from . import params
from .config.files import load_config_files
from .scenes import cases, validate_config
from .sources import source_of

#: Global attributes that may differ between two runs' files of one case.
RUN_ATTRS = ("scene", "adopted_from")
#: The manifest of a target run's adopted files, relative to ``results/{scene}``.
MANIFEST = "adopted.tsv"


class AdoptError(ValueError):
    """A source file or run that cannot be adopted; the message names it and why."""


@dataclass(frozen=True)
class Plan:
    """What adoption would do: files to copy, cases computed by both runs, cases left to run."""

    adopt: dict[str, Path]
    common: list[str]
    missing: list[str]


def expected_parameters(scene: dict) -> dict:
    """The ``scene_parameters`` a contact job of this validated scene records (JSON types)."""
    block = scene["contact"]
    # as the contact script records it: the surface file's block, then the job's settings
    return json.loads(json.dumps({"surface": params.surface(block), **params.contact(block)}))


def planned_files(scene: dict) -> dict[str, tuple[float, float, float, int]]:
    """Each contact case file name the scene plans, with its case as numbers."""
    return {f"{c.stem}.nc": (float(c.k_l), float(c.k_s), float(c.H), int(c.seed)) for c in cases(scene["contact"])}


def _attrs(ds: netCDF4.Dataset) -> dict:
    return {name: ds.getncattr(name) for name in ds.ncattrs()}


def check_source(path: Path, case: tuple, expected: dict) -> None:
    """Raise :class:`AdoptError` naming ``path`` unless it is this case's contact file made with ``expected``."""
    try:
        with netCDF4.Dataset(path) as ds:
            attrs = _attrs(ds)
            got = tuple(float(ds[d][:].item()) for d in ("k_l", "k_s", "H")) + (int(ds["seed"][:].item()),)
    except (OSError, IndexError, KeyError, ValueError) as exc:
        raise AdoptError(f"{path}: not a readable contact case file ({exc})") from None
    if attrs.get("roughcontact_stage") != "contact":
        raise AdoptError(f"{path}: stage {attrs.get('roughcontact_stage')!r}, not a contact file")
    if attrs.get("roughcontact_version") != __version__:
        raise AdoptError(f"{path}: written by roughcontact {attrs.get('roughcontact_version')!r}, this is "
                         f"{__version__}")
    if got != case:
        raise AdoptError(f"{path}: holds case (k_l, k_s, H, seed) = {got}, its name says {case}")
    recorded = json.loads(attrs.get("scene_parameters", "null"))
    if recorded != expected:
        raise AdoptError(f"{path}: made with parameters {json.dumps(recorded, sort_keys=True)}, the target scene's "
                         f"job would use {json.dumps(expected, sort_keys=True)}")


def _same_attrs(a: dict, b: dict) -> bool:
    return list(a) == list(b) and all(same_value(a[k], b[k]) for k in a)


def same_case(a: Path, b: Path) -> str | None:
    """None when two files of one case agree but for :data:`RUN_ATTRS`, else the first difference."""
    with netCDF4.Dataset(a) as x, netCDF4.Dataset(b) as y:
        if not _same_attrs(*({k: v for k, v in _attrs(d).items() if k not in RUN_ATTRS} for d in (x, y))):
            return "global attributes"
        if list(x.variables) != list(y.variables):
            return "variable names"
        for name in x.variables:
            u, v = x[name], y[name]
            if not _same_attrs(_attrs(u), _attrs(v)):
                return f"attributes of {name}"
            if u.dtype != v.dtype or not same_value(np.ma.getdata(u[:]), np.ma.getdata(v[:])):
                return f"values of {name}"
    return None


def plan(source: Path, target: Path, scene: dict) -> Plan:
    """What :func:`adopt` would do from run folder ``source`` into ``target`` (``results/{scene}``)."""
    expected = expected_parameters(scene)
    adopt, common, missing = {}, [], []
    for name, case in sorted(planned_files(scene).items()):
        src, dst = source / "contact" / name, target / "contact" / name
        if not src.is_file():
            missing.append(name)
            continue
        check_source(src, case, expected)
        if dst.is_file():
            common.append(name)
        else:
            adopt[name] = src
    return Plan(adopt, common, missing)


def copy_case(src: Path, dst: Path, scene_name: str) -> None:
    """``src`` to ``dst`` atomically, ``scene`` set to ``scene_name`` in place and ``adopted_from`` added."""
    with atomic_output(dst) as tmp:
        shutil.copyfile(src, tmp)
        with netCDF4.Dataset(tmp, "a") as ds:
            attrs = _attrs(ds)
            # netCDF moves a rewritten attribute to the end; re-creating all keeps their order
            for name in attrs:
                ds.delncattr(name)
            for name, value in {**attrs, "scene": scene_name, "adopted_from": str(src)}.items():
                ds.setncattr(name, value)


def _write_manifest(path: Path, rows: list[list[str]]) -> None:
    old = []
    if path.is_file():
        with path.open(newline="") as handle:
            old = list(csv.reader(handle, delimiter="\t"))[1:]
    merged = {row[0]: row for row in old + rows}
    buf = io.StringIO()
    writer = csv.writer(buf, delimiter="\t", lineterminator="\n")
    writer.writerow(["case_file", "source_file", "source_sha256", "sha256"])
    writer.writerows(merged[k] for k in sorted(merged))
    write_text_atomic(path, buf.getvalue())


def adopt(source: Path, target: Path, scene_name: str, scene: dict, *, trust_code: bool = False,
          dry_run: bool = False) -> Plan:
    """Copy every adoptable case of ``source`` into ``target``; returns the :class:`Plan` carried out."""
    if not (source / "contact").is_dir():
        raise AdoptError(f"{source}: no contact/ folder (give a run's results/<scene>)")
    if source.resolve() == target.resolve():
        raise AdoptError(f"{source}: source and target are the same run")
    todo = plan(source, target, scene)
    for name in todo.common:
        diff = same_case(source / "contact" / name, target / "contact" / name)
        if diff:
            raise AdoptError(f"{name}: the two runs computed this case differently ({diff}); their code differs, "
                             "so nothing is adopted")
    if todo.adopt and not todo.common and not trust_code:
        raise AdoptError("no case computed by both runs, so nothing shows that their code gives the same numbers; "
                         "run one case in the target first, or pass --trust-code")
    if dry_run or not todo.adopt:
        return todo
    rows = []
    try:
        for name, src in todo.adopt.items():
            dst = target / "contact" / name
            copy_case(src, dst, scene_name)
            rows.append([name, str(src), file_sha256(src), file_sha256(dst)])
    finally:  # an interrupted adoption still lists every copy it made
        if rows:
            _write_manifest(target / MANIFEST, rows)
    return todo


def check_adoptable(name: str, scene: dict) -> None:
    """:class:`AdoptError` unless scene ``name`` has contact cases of generated surfaces, which adoption copies,
    and nothing downstream of them reads their surfaces (``outputs.fields``: the contact map).

    A generated case is fixed by its recorded parameters and the code; a measured or array case is also
    its input file's heights, whose content a contact file does not record (its reader settings name the
    path only): adoption could not tell a case solved on an older version of the file, so it refuses.
    """
    if "contact" not in scene:
        raise AdoptError(f"scene {name!r} has no contact study, so it has no case to adopt")
    fields = scene["contact"].get("outputs", {}).get("fields")
    if fields:
        # the contact map draws its cases over their surfaces: Snakemake would regenerate an adopted case's
        # surface, and then re-solve the case, its surface being newer than its contact file
        raise AdoptError(f"scene {name!r} stores fields (contact.outputs.fields: {list(fields)}), and its contact map "
                         "reads each mapped case's surface file, which adoption does not copy: Snakemake would make "
                         "the surface again and then solve the adopted case again; adopt into a scene without "
                         f"outputs.fields, or run the scene itself (snakemake -j2 --config scene={name})")
    batch = scene["contact"]["solver"].get("batch", 1)
    if batch > 1:
        # its cases are groups of one file per batch (roughcontact.pipeline.contact_jobs), which the aggregate
        # reads: a case file copied beside them would be read by nothing
        raise AdoptError(f"scene {name!r} solves its seeds in batches (contact.solver.batch: {batch}), one file "
                         "holding each batch's cases, and adoption copies files of one case; adopt into the scene "
                         f"without solver.batch, or run it (snakemake -j2 --config scene={name})")
    source = source_of(scene, name)
    if source.key is not None:
        raise AdoptError(f"scene {name!r} takes its surfaces from its {source.key} block ({source.name} files), "
                         "and adoption copies generated cases (kl.._ks.._H.._s..) only: a file's case depends on "
                         "the file's content, which a contact file does not record; run the scene itself "
                         f"(snakemake -j2 --config scene={name})")


def _locked(workdir: Path) -> bool:
    locks = workdir / ".snakemake" / "locks"
    return locks.is_dir() and any(locks.iterdir())


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(prog="python -m roughcontact.pipeline.adopt", description=__doc__.split("\n")[0])
    ap.add_argument("source", type=Path, help="the run to take cases from, results/<scene>")
    ap.add_argument("--scene", required=True, help="the target scene (its cases go to results/<scene>)")
    ap.add_argument("--configfile", type=Path, action="append", default=[], metavar="FILE",
                    help="a config file added over config/config.yaml, as snakemake --configfile adds it (repeatable; "
                         "run from the workflow's folder: config/, results/ and .snakemake/ are there)")
    ap.add_argument("--trust-code", action="store_true", help="adopt without a case computed by both runs")
    ap.add_argument("--dry-run", action="store_true", help="say what would be adopted, copy nothing")
    args = ap.parse_args(argv)
    with input_errors(ap):
        config = load_config_files(args.configfile)
        scenes = validate_config({**config, "scene": args.scene})["scenes"]
        check_adoptable(args.scene, scenes[args.scene])
    target = Path("results") / args.scene
    if not args.dry_run:
        with input_errors(ap):  # before any case is checked or copied: a folder it cannot write fails now
            check_writable(target / MANIFEST, f"the adopted cases' list of scene {args.scene}")
    if not args.dry_run and _locked(Path.cwd()):
        ap.exit(2, f"error: a Snakemake run holds {Path.cwd()}; stop it (or let it finish), adopt, then resume\n")
    with input_errors(ap):
        done = adopt(args.source, target, args.scene, scenes[args.scene], trust_code=args.trust_code,
                     dry_run=args.dry_run)
    verb = "would adopt" if args.dry_run else "adopted"
    print(f"{verb} {len(done.adopt)} case(s) from {args.source} into {target}; {len(done.common)} computed by both "
          f"runs agree; {len(done.missing)} planned case(s) the source lacks")


if __name__ == "__main__":
    main()

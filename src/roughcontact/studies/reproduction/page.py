"""The paper's claims measured on a run: numbers, verdicts and figures for docs/reproduction/.

Pure functions over the aggregates (:func:`claims`), and the two commands of the
reproduction (``python -m roughcontact.reproduction``):

* ``publish RESULTS OUT``: copy a run's aggregates and fit (``results/{scene}/aggregate/*.nc``,
  ``fit/cel.{nc,csv}``; not the per-case files) into ``OUT/data``, then ``regenerate``;
* ``regenerate OUT``: from ``OUT/data`` alone, in seconds and without a solve, redraw the
  figures into ``OUT/figures`` (the example surfaces are regenerated from their seeds)
  and write the claim table ``OUT/claims.md``.

Every verdict states the test it applies, so a reader can disagree with a threshold
without recomputing anything.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
from pathlib import Path

import xarray as xr

from ...core.files import write_text_atomic
from ...figures.registry import FIGURES
from ...figures.style import save_figure
from ...pipeline.io import read_dataset
from .claims import claims

#: Files of a published reproduction, relative to its data folder.
DATA_FILES = ("representativity.nc", "contact.nc", "cel.nc", "cel.csv")


def markdown_table(rows: list[dict]) -> str:
    """The claim rows as a Markdown table."""
    out = ["| claim | paper | ours | verdict | test |", "|---|---|---|---|---|"]
    out += [f"| {r['claim']} | {r['paper']} | {r['ours']} | **{r['verdict']}** | {r['test']} |" for r in rows]
    return "\n".join(out) + "\n"


def _scene_tree(data: Path, tmp: Path) -> Path:
    """The published files laid out as ``results/{scene}/`` for the figure registry."""
    (tmp / "aggregate").mkdir(parents=True)
    (tmp / "fit").mkdir()
    shutil.copy(data / "representativity.nc", tmp / "aggregate" / "representativity.nc")
    shutil.copy(data / "contact.nc", tmp / "aggregate" / "contact.nc")
    shutil.copy(data / "cel.nc", tmp / "fit" / "cel.nc")
    return tmp


def _example_surfaces(rep: xr.Dataset, tmp: Path) -> list[str]:
    """The paper's Fig. 1 b-d surfaces (k_l = 1, 4, 16 at k_s = 40, seed 0), regenerated."""
    import json

    from ...pipeline.datasets import surface_dataset
    from ...pipeline.io import write_dataset
    from ...surfaces.synthetic import generate_surface

    surf = json.loads(rep.attrs["scene_parameters"])["surface"]
    norm = {k: surf[k] for k in ("rms_slope", "rms_height") if k in surf}
    paths = []
    for kl in ("1", "4", "16"):
        h = generate_surface(surf["N"], float(kl), 40.0, 0.8, 0, length=surf["L"], plateau=surf["plateau"], **norm)
        ds = surface_dataset(h, k_l=kl, k_s="40", hurst="0.8", seed=0, length=surf["L"], normalisation=norm)
        path = tmp / f"surface_{kl}.nc"
        write_dataset(ds, path, stage="surface", scene="reproduction", scene_parameters={"surface": surf})
        paths.append(str(path))
    return paths


def regenerate(out: Path) -> None:
    """Figures and claim table of ``out`` from ``out/data`` (no solve)."""
    data = out / "data"
    figs = out / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    rep = read_dataset(data / "representativity.nc", stage="aggregate", variables=["epsilon"])
    con = read_dataset(data / "contact.nc", stage="aggregate", variables=["area_fraction", "kappa"])
    fit = read_dataset(data / "cel.nc", stage="fit")
    with tempfile.TemporaryDirectory() as td:
        root = _scene_tree(data, Path(td))
        for name in ("representativity", "area_load", "kappa", "dpbar"):
            spec = FIGURES[name]
            paths = {role: str(root / p) for role, p in spec.inputs({}).items()} if name != "representativity" \
                else {"rep": str(root / "aggregate" / "representativity.nc")}
            save_figure(spec.render(paths), figs / f"{name}.png")
        surfaces = _example_surfaces(rep, Path(td))
        save_figure(FIGURES["surface_examples"].render({"surfaces": surfaces}), figs / "surface_examples.png")
    write_text_atomic(out / "claims.md", markdown_table(claims(rep, con, fit)))


def publish(results: Path, out: Path, contact_results: Path | None = None) -> None:
    """Copy a run's aggregates and fit into ``out/data``, then :func:`regenerate`.

    ``contact_results`` takes the contact aggregate and fit from another run (e.g. the
    ``representative`` scene while the ``reproduction`` scene's contact part is running).
    """
    data = out / "data"
    data.mkdir(parents=True, exist_ok=True)
    con = contact_results or results
    sources = {"representativity.nc": results / "aggregate" / "representativity.nc",
               "contact.nc": con / "aggregate" / "contact.nc",
               "cel.nc": con / "fit" / "cel.nc", "cel.csv": con / "fit" / "cel.csv"}
    for name, src in sources.items():
        if not src.is_file():
            raise FileNotFoundError(f"publish: {src} is missing; run the scene first "
                                    "(snakemake -j2 --config scene=reproduction)")
        shutil.copy(src, data / name)
    regenerate(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(prog="python -m roughcontact.reproduction", description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("publish", help="copy a run's aggregates into OUT/data, then regenerate")
    p.add_argument("results", type=Path, help="results/{scene} of a finished run")
    p.add_argument("out", type=Path, help="publication folder, e.g. docs/reproduction")
    p.add_argument("--contact-from", type=Path, default=None,
                   help="results/{scene} to take the contact aggregate and fit from instead")
    r = sub.add_parser("regenerate", help="figures and claim table from OUT/data (seconds, no solve)")
    r.add_argument("out", type=Path, help="publication folder, e.g. docs/reproduction")
    args = ap.parse_args(argv)
    if args.command == "publish":
        publish(args.results, args.out, args.contact_from)
    else:
        regenerate(args.out)


if __name__ == "__main__":
    main()

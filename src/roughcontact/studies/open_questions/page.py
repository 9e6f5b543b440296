"""docs/open-questions/: the claim table and figures, from the published aggregates alone.

``python -m roughcontact.studies.open_questions regenerate docs/open-questions`` redraws the
figures into ``figures/`` and writes ``claims.md`` from ``data/`` (seconds, no solve);
``publish RESULTS docs/open-questions`` first copies the ``full-contact`` scene's aggregate and fit
from ``RESULTS`` (``results/full-contact``) into ``data/``.
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import numpy as np

from ...core.files import write_text_atomic
from ...figures.style import save_figure
from ...pipeline.io import read_dataset
from . import analysis as an
from . import figures as fg
from .claims import row

#: Published files, relative to the page's ``data/`` folder, and where ``publish`` takes them.
DATA_FILES = {"full-contact.nc": "aggregate/contact.nc", "full-contact-cel.nc": "fit/cel.nc"}


def _pct(x: float) -> str:
    return f"{100 * x:+.1f}"


def full_contact_rows(ds, cel) -> list[dict]:
    """Q1's rows from the full-contact aggregate ``ds`` (one pair) and its fit ``cel``."""
    curve = an.pooled_curve(ds)
    const = an.cel_constants(cel)
    v = an.cel_validity(curve, const)
    onset = an.full_contact_onset(ds)
    k = int(np.argmax(np.abs(v["deviation"]) > 0.05)) if not np.all(np.abs(v["deviation"]) <= 0.05) else None
    beyond = (f"; first step beyond: A/A0 = {v['fails_at']:.3g}, CEL {_pct(v['deviation'][k])} %"
              if k is not None else "")
    first_full = curve["pbar"][np.argmax(curve["area"] >= 1.0)] if (curve["area"] >= 1.0).any() else np.nan
    rows = [row("Q1a: the CEL holds toward full contact",
                f"CEL, κ = {const['kappa']:.3f}, μ = {const['mu']:.3f}, β = {const['beta']:.3f}",
                f"within 5 % up to A/A0 = {v['holds_up_to']:.3g}{beyond}; the CEL reaches A/A0 = 1 at "
                f"p̄ = {v['cel_full']:.3g}, all {onset['n']} surfaces at p̄ = {first_full:.3g}")]
    dev = an.persson_deviation(curve)
    points = an.at_areas(curve["area"], dev, curve["pbar"])
    rows.append(row("Q1b: Persson's erf curve holds toward full contact", "A/A0 = erf(√2 p̄)",
                    "A_Persson/A − 1 " + ", ".join(f"at A/A0 = {a:g}: {_pct(d)} %" for a, (_, d) in points.items())))
    m, s = onset["pbar_fc_pooled"]
    per_h = ", ".join(f"{float(mh):.3f} ± {float(sh):.3f} (H={h:g})" for h, mh, sh in
                      zip(ds["H"].values, *onset["pbar_fc_H"], strict=True))
    rows.append(row("Q1c: full contact begins at the exact full-contact load",
                    "p_fc = −min (E*/2) F⁻¹[|q| ĥ] of each surface",
                    f"consistent in {onset['consistent']} of {onset['n']} cases; p̄_fc = {m:.3f} ± {s:.3f} "
                    f"pooled; per H: {per_h}"))
    spread = an.approach_h_spread(ds)
    n_ok = int(np.sum(spread["z"] <= 3))
    rows.append(row("Q1d: the approach to full contact is H-independent", "the same law for every H",
                    f"z ≤ 3 at {n_ok} of {spread['z'].size} steps; largest z = {spread['z'].max():.2g}, "
                    f"largest relative difference of 1 − A/A0 between H: {100 * spread['rel'].max():.0f} %"))
    tails = an.approach_tails(curve)
    rows.append(row("Q1e: Persson's erfc(√2 p̄) gives 1 − A/A0 near full contact", "1 − A/A0 = erfc(√2 p̄)",
                    f"ratio from {tails['ratio'].min():.3g} to {tails['ratio'].max():.3g} over "
                    f"{tails['ratio'].size} steps (p̄ = {tails['pbar'].min():.3g} to {tails['pbar'].max():.3g})"))
    return rows


def users_rows(ds, curves: dict) -> list[dict]:
    """Q4's rows: mean gap, stiffness, P(p) and clusters against Persson and Dapp et al."""
    def ratios(key: str) -> str:
        parts = []
        for a in (0.01, 0.1):
            items = []
            for h, c in curves.items():
                ratio = c[key] / c[f"{key}_persson"]
                items.append(f"{an.at_areas(c['area'], ratio, c['pbar'], (a,))[a][1]:.3f} (H={h:g})")
            parts.append(f"at A/A0 = {a:g}: " + ", ".join(items))
        return "; ".join(parts)

    exps = [an.stiffness_exponent(c) for c in curves.values()]
    dists = an.pressure_distributions(ds)
    perc = an.cluster_percolation(ds)
    m, s = perc["crossing"]
    return [
        row("Q4a: Persson's mean gap", "Persson (2007), Yang & Persson (2008)", "ū/ū_P " + ratios("gap")),
        row("Q4b: Persson's contact stiffness", "K = −dp0/dū of Persson's ū(p0)",
            "K/K_P " + ratios("stiffness") + "; d ln K / d ln p0 over A/A0 in [0.01, 0.1]: measured "
            + ", ".join(f"{e:.3f}" for e, _ in exps) + ", Persson " + ", ".join(f"{p:.3f}" for _, p in exps)),
        row("Q4c: Persson's P(p)", "Persson (2001), diffusion in p with magnification",
            "L1 distance " + ", ".join(f"at A/A0 = {d['area']:.3g}: {d['distance']:.3f}" for d in dists)),
        row("Q4d: the contact area percolates at A/A0 ≈ 0.42", "Dapp et al. (2012): 0.42",
            f"largest cluster holds half the contact at A/A0 = {m:.3f} ± {s:.3f} ({perc['n']} surfaces); "
            f"most clusters at A/A0 = {perc['count_peak_area']:.3g}"),
    ]


def markdown_table(rows: list[dict]) -> str:
    """The rows as the page's Markdown table."""
    out = ["| question | comparison | measured | verdict | rule |", "|---|---|---|---|---|"]
    out += [f"| {r['claim']} | {r['paper']} | {r['ours']} | **{r['verdict']}** | {r['test']} |" for r in rows]
    return "\n".join(out) + "\n"


def regenerate(out: Path) -> None:
    """Figures and ``claims.md`` of ``out`` from ``out/data`` (no solve)."""
    data, figs = out / "data", out / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    ds = an.one_pair(read_dataset(data / "full-contact.nc", stage="aggregate"))
    cel = read_dataset(data / "full-contact-cel.nc", stage="fit")
    curve = an.pooled_curve(ds)
    curves = {float(h): an.gap_and_stiffness(ds, float(h)) for h in ds["H"].values}
    save_figure(fg.area_figure(curve, an.cel_validity(curve, an.cel_constants(cel)), an.full_contact_onset(ds)),
                figs / "full_contact.png")
    save_figure(fg.gap_stiffness_figure(curves), figs / "gap_stiffness.png")
    save_figure(fg.pressure_figure(an.pressure_distributions(ds)), figs / "pressure_distribution.png")
    save_figure(fg.cluster_figure(an.cluster_percolation(ds)), figs / "clusters.png")
    write_text_atomic(out / "claims.md", markdown_table(full_contact_rows(ds, cel) + users_rows(ds, curves)))


def publish(results: Path, out: Path) -> None:
    """Copy the run's aggregate and fit (:data:`DATA_FILES`) into ``out/data``, then :func:`regenerate`."""
    data = out / "data"
    data.mkdir(parents=True, exist_ok=True)
    for name, source in DATA_FILES.items():
        shutil.copyfile(results / source, data / name)
    regenerate(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(prog="python -m roughcontact.studies.open_questions", description=__doc__)
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("regenerate", help="figures and claims.md from OUT/data").add_argument("out", type=Path)
    pub = sub.add_parser("publish", help="copy a full-contact run's aggregate and fit, then regenerate")
    pub.add_argument("results", type=Path)
    pub.add_argument("out", type=Path)
    args = ap.parse_args(argv)
    if args.command == "publish":
        publish(args.results, args.out)
    else:
        regenerate(args.out)

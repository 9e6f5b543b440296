"""The κ-gap study's page ``kappa-gap.md``: tables, conclusion, and the command line that regenerates or publishes it.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from ...analysis.fit.estimators import PAPER_CEL
from ...core.cli import input_errors, require_files, require_folder
from .analysis import CLOSES_RULE, pct, summarise
from .cases import KAPPA_BGT, TARGET_AREAS

SECTIONS = {"solver": "1. solver", "definition": "2. contact", "continuum": "3. continuum",
            "convention": "4. convention"}


COMMANDS = (
    ("run the study (or resume it)",
     "`snakemake -j2 --config scene=kappa-gap`"),
    ("regenerate this page from the published data (no solve)",
     "`python -m roughcontact.studies.kappa_gap regenerate docs/reproduction`"),
    ("publish a finished run here",
     "`python -m roughcontact.studies.kappa_gap publish results/kappa-gap docs/reproduction`"),
)


def _k(x: float) -> str:
    return f"{x / KAPPA_BGT:.4f}" if np.isfinite(x) else "—"


def _areas_header(what: str) -> str:
    return " | ".join(f"{what} {a:g}" for a in TARGET_AREAS)


def _gap_table(s: dict) -> list[str]:
    m = s["meta"]
    lines = [f"| A/A0 | paper's CEL κ/√(2π) | ours κ/√(2π) (N = {m['N']}, p > 0, {s['n_base']} surfaces) | "
             "ours − paper [%] |", "|---|---|---|---|"]
    for i, a in enumerate(TARGET_AREAS):
        lines.append(f"| {a:g} | {_k(s['paper'][i])} | {_k(s['kappa_base'][i])} | "
                     f"{pct(s['gap'][i], s['gap_se'][i])} |")
    lines.append(f"| CEL fit, μ = 0.55 and β = 0.21 held | {PAPER_CEL['kappa'][0] / KAPPA_BGT:.3f} | "
                 f"{_k(s['fit_base'])} | {100 * (s['fit_base'] / PAPER_CEL['kappa'][0] - 1):+.2f} |")
    return lines


def _candidates_table(s: dict) -> list[str]:
    head = ("| cause | candidate | " + _areas_header("κ shift [%] at A/A0 =") +
            " | surfaces | κ/√(2π), CEL fit with μ, β held | closes the gap? |")
    lines = [head, "|---|---|" + "---|" * len(TARGET_AREAS) + "---|---|---|"]
    for r in s["rows"]:
        shifts = " | ".join(pct(m, e) for m, e in zip(r["shift"], r["se"], strict=True))
        lines.append(f"| {SECTIONS[r['section']]} | {r['candidate']} | {shifts} | {r['n']} | {_k(r['fit'])} | "
                     f"{r['closes']} |")
    return lines


def _mean_se(k: np.ndarray) -> str:
    ok = np.all(np.isfinite(k), axis=1)
    if ok.sum() < 2:
        return " | ".join("—" for _ in TARGET_AREAS)
    return " | ".join(f"{_k(m)} ± {e / KAPPA_BGT:.4f}" for m, e in
                      zip(k[ok].mean(axis=0), k[ok].std(axis=0, ddof=1) / math.sqrt(ok.sum()), strict=True))


def _continuum_table(s: dict) -> list[str]:
    lines = ["| N | λ_s/Δx | surfaces | area | " + _areas_header("κ/√(2π) at A/A0 =") + " |",
             "|---|---|---|---|" + "---|" * len(TARGET_AREAS)]
    ks = float(s["meta"]["k_s"])
    for d, name in (("pressure", "pixels"), ("corrected", "perimeter-corrected")):
        c = s[f"continuum_{d}"]
        for i, n in enumerate(c["N"]):
            k = c["kappa"][i]
            lines.append(f"| {n} | {n / ks:g} | {int(np.all(np.isfinite(k), axis=1).sum())} | {name} | {_mean_se(k)} |")
        cells = " | ".join(f"**{_k(m)} ± {e / KAPPA_BGT:.4f}** (order {o:.2f})" if np.isfinite(o) else
                           "— (differences do not shrink)" for m, e, o in zip(c["limit"], c["limit_se"], c["order"],
                                                                              strict=True))
        lines.append(f"| ∞ (Richardson, last three N) | ∞ | {c['n_shared']} | {name} | {cells} |")
    return lines


def _solver_lines(s: dict) -> list[str]:
    lines = ["| stopping tolerance | N | iterations per surface, Stanley & Kato / ours | stopped by its rule | "
             "largest load error | A/A0 ratio to ours, range |", "|---|---|---|---|---|---|"]
    for d in s["solver_detail"]:
        lines.append(f"| {d['tol']} | {d['N']} | {d['iterations']:.0f} / {d['ref_iterations']:.0f} | "
                     f"{'every step' if d['stopped'] else 'not every step'} | {100 * d['load_error_max']:.3f} % | "
                     f"{d['area_ratio_min']:.4f} – {d['area_ratio_max']:.4f} |")
    return lines


def _load_lines(s: dict) -> list[str]:
    out = []
    for d in s.get("loads", []):
        out.append(f"- 30 uniform steps to p0/E* = {d['p_max']:g} ({d['n']} surfaces): A/A0 at the final load "
                   f"{100 * d['final_mean']:.1f} % (range {100 * d['final_min']:.1f}–{100 * d['final_max']:.1f} %), "
                   f"{100 * d['first_mean']:.1f} % already at the first step; {d['in_window']:.1f} of the 30 steps "
                   "per surface fall inside the paper's fit window A/A0 ∈ [0.01, 0.11].")
    return out


def _cost_lines(s: dict) -> list[str]:
    lines = ["| variant | role | N | solver | surfaces | iterations, total / per surface | "
             "work, N² × iterations [10⁹] |", "|---|---|---|---|---|---|---|"]
    for c in s["cost"]:
        lines.append(f"| {c['label']} | {c['role']} | {c['N']} | {c['method']} | {c['cases']} | "
                     f"{c['iterations']} / {c['per_case']:.1f} | {c['node_iterations'] / 1e9:.2f} |")
    total = sum(c["node_iterations"] for c in s["cost"])
    lines.append(f"| all | | | | {sum(c['cases'] for c in s['cost'])} | "
                 f"{sum(c['iterations'] for c in s['cost'])} | {total / 1e9:.2f} |")
    return lines


def _per_area(values: np.ndarray, se: np.ndarray | None = None) -> str:
    """"a, b, c and d %" over :data:`TARGET_AREAS` (± s.e. when given)."""
    cells = [f"{100 * v:+.2f}" + (f" ± {100 * e:.2f}" if se is not None and np.isfinite(e) else "")
             if np.isfinite(v) else "—" for v, e in zip(values, se if se is not None else values, strict=True)]
    return ", ".join(cells[:-1]) + f" and {cells[-1]} %"


def conclusion(s: dict) -> str:
    """The closing paragraph, from the numbers: which candidates move κ toward the paper, what remains."""
    needed = 1.0 / (1.0 + s["gap"]) - 1.0
    needed_se = s["gap_se"] / (1.0 + s["gap"]) ** 2
    areas = ", ".join(f"{a:g}" for a in TARGET_AREAS)
    text = (f"**Conclusion.** To lie on the paper's law our κ (N = {s['meta']['N']}, nodes with p > 0) would have "
            f"to rise by {_per_area(needed, needed_se)} at A/A0 = {areas}; the one-constant CEL fit (μ, β held "
            f"at the paper's values) is {100 * (s['fit_base'] / PAPER_CEL['kappa'][0] - 1):+.1f} % from the "
            "paper's κ. ")
    helps = [r for r in s["rows"] if r["closes"] != "**no**"]
    others = [r for r in s["rows"] if r["closes"] == "**no**"]
    for r in helps:
        rest = needed - r["shift"]
        text += (f"{r['candidate'][0].upper()}{r['candidate'][1:]} ({r['closes'][2:-2]}) raises it by "
                 f"{_per_area(r['shift'])}, leaving {_per_area(rest, np.hypot(needed_se, r['se']))}. ")
    if not helps:
        text += "No candidate moves κ toward the paper's value by the rule above. "
    text += ("These do not: " + "; ".join(f"{r['candidate']} ({pct(r['shift'][2], r['se'][2])} % at 0.05)"
                                        for r in others) + ". ")
    i = TARGET_AREAS.index(0.05)
    c = s["continuum_pressure"]
    if np.isfinite(c["order"][i]):
        limit = c["limit"][i]
        text += (f"The continuum limit of κ(0.05) is {_k(limit)} √(2π) ± {c['limit_se'][i] / KAPPA_BGT:.4f} "
                 f"(pixel-counted areas extrapolated at order {c['order'][i]:.2f}); our N = {s['meta']['N']} "
                 f"value lies {100 * (s['kappa_base'][i] / limit - 1):+.1f} % above it and the paper's law "
                 f"{100 * (s['paper'][i] / limit - 1):+.1f} %: pixel counting at λ_s/Δx = "
                 f"{s['meta']['N'] / float(s['meta']['k_s']):g} inflates κ by more than the gap between the "
                 "two studies.")
    return text


def markdown(summary: dict) -> str:
    """``kappa-gap.md`` from :func:`summarise`'s numbers."""
    s, m = summary, summary["meta"]
    sk_n = sorted({d["N"] for d in s["solver_detail"]})
    lines = [
        f"# The κ gap at the representative point (k_l = {m['k_l']}, k_s = {m['k_s']})", "",
        "Generated by `python -m roughcontact.studies.kappa_gap` from the `kappa-gap` scene's data "
        "(`data/kappa-gap.nc`). Every number is measured on the same continuous surfaces "
        f"(k_l = {m['k_l']}, k_s = {m['k_s']}, rms slope {m['rms_slope']:g}, H = {m['H']}), each candidate "
        "paired surface by surface with our default: shifts are means over surfaces of the paired ratio − 1, "
        "± their standard errors. Loads: 30 uniform steps to p0/E* = "
        f"{m['p_max']:g} unless a row says otherwise (the paper prints 0.05: see the last row and "
        "config/README.md). κ = E* h' A/(A0 p0) with the spectral rms slope h', interpolated linearly in "
        "log A between load steps.", "",
        "| what | command |", "|---|---|", *[f"| {a} | {b} |" for a, b in COMMANDS], "",
        "## The gap to explain", "", *_gap_table(s), "",
        "## The candidates, one at a time", "",
        f"Each row: how far the candidate moves κ(A/A0) from ours (N = {m['N']}, p > 0). A positive shift "
        "is toward the paper.", "",
        *_candidates_table(s), "", CLOSES_RULE + ".", "",
        "### 1. The paper's solver", "",
        "Stanley & Kato's (1997) displacement iteration (`roughcontact.solver.reference.stanley_kato`: a projected "
        "gradient on the displacement, relaxation 1, stopped when the carried load and the displacement "
        "change are both within the tolerance), each load step warm-started like ours, against our solver "
        f"on the same surfaces and loads, at N = {', '.join(map(str, sk_n))}: its iteration count grows with "
        "N, as a plain gradient method's must.", "",
        *_solver_lines(s), "",
        "### 3. The continuum limit", "",
        "The same continuous surfaces at each N (the noise is drawn on the smallest grid holding the "
        "band), 12 geometric load steps to the same final load; Richardson's extrapolation per area from "
        "the surface means of the last three N, its standard error from 1000 bootstrap resamples of the "
        "surfaces.", "", *_continuum_table(s), "",
        "### 4. The paper's printed load", "", *_load_lines(s), "",
        "## Cost", "",
        ("What the solves took, counted so that a rerun writes the same page: the solver's iterations over every "
         "step of every surface (an iteration of either solver is about one FFT pair over the N² nodes) "
         "and their work, N² × iterations. The jobs' wall times are in Snakemake's benchmark files: "
         "`python -m roughcontact.pipeline.runcost results/kappa-gap`."), "",
        *_cost_lines(s), "", conclusion(s), "",
    ]
    return "\n".join(lines)


def regenerate(out: Path) -> Path:
    """Rewrite ``out/kappa-gap.md`` from ``out/data/kappa-gap.nc``; returns the page's path."""
    from ...core.files import write_text_atomic
    from ...pipeline.io import read_dataset

    require_folder(out, "the page's folder, e.g. docs/reproduction")
    require_files(Path(out) / "data", ["kappa-gap.nc"], "regenerate reads OUT/data/kappa-gap.nc (publish a run first)")
    data = read_dataset(Path(out) / "data" / "kappa-gap.nc", stage="kappa_gap")
    page = Path(out) / "kappa-gap.md"
    write_text_atomic(page, markdown(summarise(data)))
    return page


def publish(results: Path, out: Path) -> Path:
    """Copy a finished run's ``kappa_gap/kappa-gap.nc`` into ``out/data`` (byte for byte) and regenerate."""
    import shutil

    from ...core.files import atomic_output
    from ...pipeline.io import read_dataset

    src = Path(results) / "kappa_gap" / "kappa-gap.nc"
    require_files(src.parent, [src.name], "give a finished kappa-gap run's results folder, e.g. results/kappa-gap")
    read_dataset(src, stage="kappa_gap")  # a clear error for a missing or foreign file
    with atomic_output(Path(out) / "data" / "kappa-gap.nc") as tmp:
        shutil.copyfile(src, tmp)
    return regenerate(out)


def main(argv=None) -> None:
    """``python -m roughcontact.studies.kappa_gap regenerate OUT`` or ``publish RESULTS OUT``."""
    ap = argparse.ArgumentParser(prog="python -m roughcontact.studies.kappa_gap", description=main.__doc__)
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("regenerate", help="rewrite OUT/kappa-gap.md from OUT/data").add_argument("out", type=Path)
    pub = sub.add_parser("publish", help="copy a finished run's data into OUT/data and regenerate")
    pub.add_argument("results", type=Path)
    pub.add_argument("out", type=Path)
    args = ap.parse_args(argv)
    with input_errors(ap):
        page = regenerate(args.out) if args.command == "regenerate" else publish(args.results, args.out)
    print(page)


if __name__ == "__main__":
    main()

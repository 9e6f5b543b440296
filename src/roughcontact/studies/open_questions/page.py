"""docs/open-questions/: the claim table and figures, from the published aggregates alone.

``python -m roughcontact.studies.open_questions regenerate docs/open-questions`` redraws the
figures into ``figures/`` and writes ``claims.md`` from ``data/`` (seconds, no solve);
``publish results/full-contact results/representative-2L results/kappa-alpha docs/open-questions``
(the last folder is the page) first copies the three scenes' aggregates and the full-contact fit
into ``data/``. Q2 and Q3 also read two aggregates the reproduction publishes (:data:`REPRODUCTION`).
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import numpy as np

from ...core.cli import input_errors, require_files, require_folder
from ...core.files import check_writable, write_text_atomic
from ...figures.style import save_figure
from ...pipeline.io import read_dataset
from . import analysis as an, figures as fg, kappa as kp
from .claims import row

#: Published files, relative to the page's ``data/`` folder, and where ``publish`` takes them in a run
#: (``results/full-contact``, and ``results/representative-2L`` for the last).
DATA_FILES = {"full-contact.nc": "aggregate/contact.nc", "full-contact-cel.nc": "fit/cel.nc",
              "representative-2L.nc": "aggregate/contact.nc", "kappa-alpha.nc": "aggregate/contact.nc",
              "kappa-alpha-4096.nc": "aggregate/contact.nc", "percolation.nc": "aggregate/contact.nc",
              "percolation-2048.nc": "aggregate/contact.nc", "persson-modes-256.nc": "aggregate/contact.nc",
              "persson-modes-512.nc": "aggregate/contact.nc"}

#: The runs that may still be going when a page is published: their rows then read "pending".
OPTIONAL = ("representative-2L.nc", "kappa-alpha.nc", "kappa-alpha-4096.nc", "percolation.nc",
            "percolation-2048.nc", "persson-modes-256.nc", "persson-modes-512.nc")

#: The scenes whose aggregates (``aggregate/contact.nc``) ``publish --run FILE=RUN`` takes beyond the first three.
MORE_RUNS = ("kappa-alpha-4096.nc", "percolation.nc", "percolation-2048.nc", "persson-modes-256.nc",
             "persson-modes-512.nc")

#: The mode-count cells of Q4a/Q4b (32 pixels per λ_s, k_s = 2 k_l): data file and k_l.
MODE_CELLS = {"persson-modes-256.nc": 4, "persson-modes-512.nc": 8}

#: Aggregates published by the reproduction that Q2 and Q3 read, relative to ``docs/``: the paper
#: grid (its λ_s = 32 Δx column) and the reproduction's L = 1 representative cells.
REPRODUCTION = {"grid": "reproduction/paper-grid/data/contact.nc", "small": "reproduction/data/contact.nc"}


def _pct(x: float) -> str:
    return f"{100 * x:+.1f}"


def _crossing(percent: str, crossing: tuple) -> str:
    """A tolerance crossing of the CEL (:func:`analysis.tolerance_crossing`) with the steps that bound it."""
    at, lo, hi = crossing
    if np.isnan(at):
        return f"{percent} % crossing at A/A0 = {lo:.3g} or beyond (none up to the last step)"
    if np.isnan(lo):
        return f"{percent} % crossing at A/A0 = 0 (the first step, {hi:.3g}, is beyond)"
    return f"{percent} % crossing at A/A0 = {at:.3f} (interpolated between the steps at {lo:.3f} and {hi:.3f})"


def full_contact_rows(ds, cel) -> list[dict]:
    """Q1's rows from the full-contact aggregate ``ds`` (one pair) and its fit ``cel``."""
    curve = an.pooled_curve(ds)
    const = an.cel_constants(cel)
    v = an.cel_validity(curve, const)
    onset = an.full_contact_onset(ds)
    k = int(np.argmax(np.abs(v["deviation"]) > 0.05)) if not np.all(np.abs(v["deviation"]) <= 0.05) else None
    beyond = (f"; first step beyond: A/A0 = {v['fails_at']:.3g}, CEL {_pct(v['deviation'][k])} %"
              if k is not None else "")
    m_fc = onset["pbar_fc"].max()
    rows = [row("Q1a: the CEL holds toward full contact",
                f"CEL, κ = {const['kappa']:.3f}, μ = {const['mu']:.3f}, β = {const['beta']:.3f}",
                f"within 5 % up to A/A0 = {v['holds_up_to']:.3g}{beyond}; {_crossing('5', v['crossing'])}; "
                f"{_crossing('4', v['crossing_sensitivity'])}; the CEL reaches A/A0 = 1 at p̄ = "
                f"(1 − β)^(1/(μ−1))/κ = {v['cel_full']:.3f}, the surfaces at p̄_fc ≤ {float(m_fc):.3g} (Q1c)")]
    dev = an.persson_deviation(curve)
    points = an.at_areas(curve["area"], dev, curve["pbar"])
    rows.append(row("Q1b: Persson's erf curve holds toward full contact", "A/A0 = erf(√2 p̄)",
                    "A_Persson/A − 1 " + ", ".join(f"at A/A0 = {a:g}: {_pct(d)} %" for a, (_, d) in points.items())))
    m, s = onset["pbar_fc_pooled"]
    per_h = ", ".join(f"{float(mh):.3f} ± {float(sh):.3f} (H={h:g})" for h, mh, sh in
                      zip(ds["H"].values, *onset["pbar_fc_H"], strict=True))
    rows.append(row("Q1c: full contact begins at the exact full-contact load",
                    "p_fc = −min (E*/2) F⁻¹[‖q‖ ĥ] of each surface",
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


def _bands(curves: dict, key: str, spectrum: str, areas=(0.01, 0.1)) -> str:
    """``value [low, high] (H=h)`` of measured over Persson's ``key`` at each of ``areas``: γ = 0.45 and its band."""
    parts = []
    for a in areas:
        items = []
        for h, c in curves.items():
            band = an.persson_ratio_band(c, key, spectrum, a)
            items.append(f"{band[an.GAMMAS.index(an.GAMMA)]:.3f} [{min(band):.3f}, {max(band):.3f}] (H={h:g})")
        parts.append(f"at A/A0 = {a:g}: " + ", ".join(items))
    return "; ".join(parts)


def _mode_count(modes: dict, key: str) -> str:
    """The mode-count cells' bands at A/A0 = 0.01 (expected spectrum) and their seed errors, or what is pending."""
    missing = [f"k_l = {kl} (scene {name[:-3]})" for name, kl in MODE_CELLS.items() if name not in modes]
    done = [f"k_l = {MODE_CELLS[name]}, k_s = {2 * MODE_CELLS[name]}: " + _bands(curves, key, "expected", (0.01,))
            + ", seed standard error of the measured value " + ", ".join(
                f"{100 * an.relative_sem(c, key, 0.01):.1f} %" for c in curves.values())
            for name, curves in modes.items()]
    text = "mode count (32 px per λ_s, expected spectrum): k_l = 16, k_s = 32 above"
    text += "".join(f"; {d}" for d in done)
    return text + (f"; pending: {', '.join(missing)}" if missing else "")


def _discretisation(curves: dict, modes: dict, key: str) -> str:
    """The ratios at γ = 0.45, expected spectrum, A/A0 = 0.01, with each w(q) of :data:`analysis.W_SENSITIVITY`."""
    cells = {16: curves} | {MODE_CELLS[name]: c for name, c in modes.items()}
    names = {"shell": "whole shell", "mode": "per mode", "continuum": "continuum power law"}
    parts = [f"k_l = {kl}: " + ", ".join(" / ".join(f"{an.persson_ratio(c, key, ('rule', r), 0.01):.3f}"
                                                     for r in an.W_SENSITIVITY) + f" (H={h:g})"
                                         for h, c in cs.items()) for kl, cs in cells.items()]
    return (f"w(q) discretisation at γ = 0.45, expected spectrum, A/A0 = 0.01 "
            f"({' / '.join(names[r] for r in an.W_SENSITIVITY)}): " + "; ".join(parts))


def percolation_text(perc: dict) -> str:
    """The definitions' thresholds of :func:`analysis.percolation_definitions`, as the row prints them."""
    d = perc["definitions"]
    return ", ".join(f"{an.WRAPPING_DEFINITIONS[k][0]} {d[k]['threshold']:.4f}" for k in an.WRAPPING_DEFINITIONS)


def users_rows(ds, curves: dict, perc: dict, perc_fine: dict | None = None, modes: dict | None = None) -> list[dict]:
    """Q4's rows: mean gap, stiffness, P(p) and clusters against Persson and Dapp et al.

    ``perc``: :func:`analysis.percolation_definitions` of the percolation data (the ``percolation``
    scene's wrapping), or :func:`analysis.percolation_threshold` of the full-contact scene's
    largest-cluster proxy; ``perc_fine`` the definitions of the N = 2048 cells; ``modes``: the
    mode-count cells' curves by data file.
    """
    modes = modes or {}

    def persson(key: str) -> str:
        return (f"{'ū/ū_P' if key == 'gap' else 'K/K_P'} as γ = 0.45 [γ band 0.4–0.5], w(q) at the middle of each "
                "shell's power: expected spectrum " + _bands(curves, key, "expected") + "; measured spectra "
                + _bands(curves, key, "measured") + "; " + _mode_count(modes, key) + "; "
                + _discretisation(curves, modes, key))

    exps = [an.stiffness_exponent(c) for c in curves.values()]
    dists = an.pressure_distributions(ds)
    counts = an.cluster_counts(ds)
    if "definitions" in perc:
        one = perc["definitions"]["either"]
        fine = ("" if perc_fine is None else f"; at N = 2048 (λ_s = 64 Δx, {perc_fine['n']} surfaces): one direction "
                f"{perc_fine['threshold']:.3f}, " + percolation_text(perc_fine))
        wraps = (f"first wrapping of a 4-connected cluster (cluster_wrapping), per surface: in x or y between the "
                 f"steps at A/A0 = {one['below_mean']:.3f} → {one['at_mean']:.3f} (means; {one['below'][0]:.3f}–"
                 f"{one['below'][1]:.3f} → {one['at'][0]:.3f}–{one['at'][1]:.3f}); threshold by definition: "
                 f"{percolation_text(perc)}; threshold A/A0 = {perc['threshold']:.3f} ± {perc['u']:.3f} (one "
                 f"direction, as Dapp et al.: mean of in x and in y; 8-connected: {perc['dual']:.4f}; {perc['n']} "
                 f"surfaces; u the largest of the definitions' half-range {perc['half_range']:.4f}, half the widest "
                 f"bracket {perc['half_step']:.4f}, seed standard error {perc['sem']:.4f}){fine}")
    else:
        wraps = (f"largest-cluster share crossing half (proxy; no wrapping data yet): per surface between the steps at "
                 f"A/A0 = {perc['below_mean']:.3f} → {perc['at_mean']:.3f}; threshold A/A0 = {perc['threshold']:.3f} ± "
                 f"{perc['u']:.3f} ({perc['n']} surfaces; half the widest bracket {perc['half_step']:.3f}, seed "
                 f"standard error {perc['sem']:.3f})")
    return [
        row("Q4a: Persson's mean gap", "Persson (2007), Yang & Persson (2008)", persson("gap")),
        row("Q4b: Persson's contact stiffness", "K = −dp0/dū of Persson's ū(p0)",
            persson("stiffness") + "; d ln K / d ln p0 over A/A0 in [0.01, 0.1] (γ = 0.45, expected): measured "
            + ", ".join(f"{e:.3f}" for e, _ in exps) + ", Persson " + ", ".join(f"{p:.3f}" for _, p in exps)),
        row("Q4c: Persson's P(p)", "Persson (2001), diffusion in p with magnification",
            "L1 distance " + ", ".join(f"at A/A0 = {d['area']:.3g}: {d['distance']:.3f}" for d in dists)),
        row("Q4d: the contact area percolates at A/A0 ≈ 0.42", "Dapp et al. (2012): 0.42, one direction (where the "
            "leakage stops); later work ≈ 0.415", f"{wraps}; most clusters at A/A0 = {counts['count_peak_area']:.3g}"),
    ]


def _pending(question: str, scene: str) -> dict:
    return {"claim": question, "paper": "—", "ours": f"not yet run: needs the {scene} scene", "verdict": "pending",
            "test": "—"}


def trend_row(grid, extra) -> dict:
    """Q2d: the N = 2048 points (k_s = 64) against the paper grid's λ_s = 32 Δx trend in ln α."""
    question = "Q2d: at equal α, λ_l = L/8 and L/4 cells (N = 2048) follow the N = 1024 trend"
    if extra is None:
        return _pending(question, "kappa-alpha")
    new = kp.alpha_points(extra, 64.0)
    test = kp.trend_test(kp.alpha_points(grid, 32.0), new)
    points = ", ".join(f"z = {z:+.2f} (λ_l = L/{kl:g}, H = {h:g}, α = {a:.3g}, κ/√2π = {k:.3f})"
                       for z, kl, h, a, k in zip(test["z"], new["k_l"], new["H"], new["alpha"], new["kappa"],
                                                 strict=True))
    return row(question, "the line through the 20 points at N = 1024", f"{points}; scatter s = {test['scatter']:.4f}")


#: Q2e's question: is κ's fall linear in ln α over every point at 32 px per λ_s?
RANGE_QUESTION = "Q2e: κ falls linearly in ln α over the whole range, N = 1024 to 4096 at 32 px per λ_s"


def bend_text(label: str, fit: dict) -> str:
    """One set of :func:`kappa.bend` fits as the Q2e row prints it."""
    m, e, c, ce, n = fit["all"]
    bm, be, bn = fit["below"]
    am, ae, ac, ace, an_ = fit["above"]
    s = fit["split"]
    return (f"{label}: all {n} points (α = {fit['range'][0]:.3g} to {fit['range'][1]:.3g}): slope = {m:.4f} ± "
            f"{e:.4f}, curvature = {c:.4f} ± {ce:.4f}; α < {s:g} ({bn} points): slope = {bm:.3f} ± {be:.3f}; "
            f"α ≥ {s:g} ({an_} points): slope = {am:.4f} ± {ae:.4f}, curvature = {ac:.4f} ± {ace:.4f}")


def _range_points(grid, extra, big, area=lambda con: con) -> dict:
    """Every point at 32 px per λ_s (:func:`kappa.alpha_points`) of ``area`` (the pixel-counted or corrected κ)."""
    return kp.merged_points(kp.alpha_points(area(grid), 32.0),
                            *([kp.alpha_points(area(extra), 64.0)] if extra is not None else []),
                            kp.alpha_points(area(big), 128.0))


def _bends(grid, extra, big) -> tuple | None:
    """:func:`kappa.bend` of the pixel-counted and the corrected points (Q2e's figure lines), None without N = 4096."""
    return None if big is None else tuple(kp.bend(_range_points(grid, extra, big, area))
                                          for area in (lambda con: con, kp.corrected))


def range_row(grid, extra, big) -> dict:
    """Q2e: κ(0.05) against ln α over every point at 32 px per λ_s, the N = 4096 cells (k_s = 128) included.

    The fits over all points, below and above :data:`kappa.BEND_SPLIT` (:func:`kappa.bend`), with
    each point's measured α (the main line), the perimeter-corrected κ and the expected lattice
    spectrum's α (the sensitivities).
    """
    if big is None:
        return _pending(RANGE_QUESTION, "kappa-alpha-4096 (75 cases at N = 4096, 11.8 CPU-hours measured)")

    pixel = _range_points(grid, extra, big)
    main = kp.bend(pixel)
    a_top, line, line_se, measured, z = main["line_top"]
    fits = [bend_text("pixel-counted, measured α", main),
            f"the α ≥ {main['split']:g} line at α = {a_top:.3g}: {line:.3f} ± {line_se:.3f}, measured {measured:.3f}, "
            f"z = {z:+.2f}",
            bend_text("perimeter-corrected, measured α", kp.bend(_range_points(grid, extra, big, kp.corrected))),
            bend_text("pixel-counted, expected lattice α", kp.bend(pixel, "alpha_lattice"))]
    models = ", ".join(f"{name} {kp.log_slope(pixel['alpha'], pixel[key])[0]:.3f}"
                       for name, key in (("BGT", "bgt"), ("Greenwood", "greenwood")))
    top = int(np.argmax(pixel["alpha"]))
    return row(RANGE_QUESTION, f"asperity models over the same α: {models}",
               f"{'; '.join(fits)} (√2π per e-fold of α); at the largest α κ/√2π = {pixel['kappa'][top]:.3f} "
               f"(pixel-counted), BGT {pixel['bgt'][top]:.3f}, Greenwood {pixel['greenwood'][top]:.3f}")


def alpha_rows(grid) -> list[dict]:
    """Q2's rows from the paper grid's k_s = 32 column (N = 1024: λ_s = 32 Δx)."""
    rows = []
    for label, con in (("pixel-counted area", grid), ("perimeter-corrected area", kp.corrected(grid))):
        pts = kp.alpha_points(con, 32.0)
        m, e = kp.log_slope(pts["alpha"], pts["kappa"], pts["sem"])
        models = ", ".join(f"{name} {kp.log_slope(pts['alpha'], pts[key])[0]:.3f}"
                           for name, key in (("BGT", "bgt"), ("Greenwood", "greenwood")))
        rows.append(row(f"Q2a: κ depends on α at fixed resolution ({label})" if label.startswith("pixel") else
                        f"Q2b: κ depends on α at fixed resolution ({label})", f"asperity models: {models}",
                        f"slope = {m:.4f} ± {e:.4f} (√2π per e-fold of α) over {pts['alpha'].size} points, α = "
                        f"{pts['alpha'].min():.3g} to {pts['alpha'].max():.3g}"))
    pts = kp.alpha_points(grid, 32.0)
    near = {name: int(np.sum(np.abs(pts[key] / pts["kappa"] - 1) <= 0.05)) for name, key in
            (("BGT", "bgt"), ("Greenwood", "greenwood"))}
    n = pts["alpha"].size
    rows.append(row("Q2c: BGT and Greenwood give κ at the surfaces' own α", "Nayak statistics at each surface's α",
                    f"within 5 % of BGT at {near['BGT']} of {n} points, within 5 % of Greenwood at "
                    f"{near['Greenwood']} of {n} points; at the largest α ({pts['alpha'].max():.3g}) κ/√2π = "
                    f"{pts['kappa'][np.argmax(pts['alpha'])]:.3f}, BGT {pts['bgt'][np.argmax(pts['alpha'])]:.3f}"))
    return rows


def cell_rows(small, large) -> list[dict]:
    """Q3's rows: the representative spectrum on L and 2L cells (same pixel); pending without the 2L run."""
    if large is None:
        return [_pending(q, "representative-2L") for q in ("Q3a: κ is the same on L and 2L cells",
                                                           "Q3b: κ's seed scatter halves on a 2L cell")]
    comp = kp.cell_size_comparison(small, large)
    ok = sum(abs(r["z"]) <= 2 for r in comp)
    diffs = [r["large"][0] - r["small"][0] for r in comp]
    at05 = [r for r in comp if r["area"] == 0.05]
    return [
        row("Q3a: κ is the same on L and 2L cells", "a representative cell: no change with its size",
            f"abs(z) ≤ 2 at {ok} of {len(comp)} points; Δκ/√2π from {min(diffs):+.4f} to {max(diffs):+.4f}; "
            + "; ".join(f"κ(0.05)/√2π {r['small'][0]:.4f} ± {r['small'][1]:.4f} (L) and {r['large'][0]:.4f} ± "
                        f"{r['large'][1]:.4f} (2L) at H = {r['H']:g}" for r in at05)),
        row("Q3b: κ's seed scatter halves on a 2L cell", "1/√4 = 0.5 for a self-averaging κ",
            "s.d. ratio 2L/L of κ(0.05): " + ", ".join(
                f"{r['sd_ratio'][0]:.3f} [{r['sd_ratio'][1]:.3f}, {r['sd_ratio'][2]:.3f}] at H = {r['H']:g}"
                for r in at05)),
    ]


def markdown_table(rows: list[dict]) -> str:
    """The rows as the page's Markdown table."""
    out = ["| question | comparison | measured | verdict | rule |", "|---|---|---|---|---|"]
    out += [f"| {r['claim']} | {r['paper']} | {r['ours']} | **{r['verdict']}** | {r['test']} |" for r in rows]
    return "\n".join(out) + "\n"


def _reproduction(docs: Path) -> dict:
    """The reproduction's aggregates Q2 and Q3 read (:data:`REPRODUCTION`) under ``docs``."""
    grid = read_dataset(docs / REPRODUCTION["grid"], stage="aggregate")
    small = read_dataset(docs / REPRODUCTION["small"], stage="aggregate").sel(k_l=[16.0], k_s=[32.0])
    return {"grid": grid, "small": an.one_pair(small)}


def _optional(data: Path, name: str):
    """The published aggregate ``data/name`` (one pair), or None while its run is pending."""
    path = data / name
    return an.one_pair(read_dataset(path, stage="aggregate")) if path.exists() else None


def regenerate(out: Path, docs: Path | None = None) -> None:
    """Figures and ``claims.md`` of ``out`` from ``out/data`` and the reproduction's aggregates (no solve).

    ``docs`` is the folder holding ``reproduction/`` (default: ``out``'s parent).
    """
    data, figs = out / "data", out / "figures"
    docs = out.parent if docs is None else docs
    require_folder(out, "the page's folder, e.g. docs/open-questions")
    require_files(data, [n for n in DATA_FILES if n not in OPTIONAL], "regenerate reads the published data in "
                  "OUT/data (publish a run there first)")
    require_files(docs, list(REPRODUCTION.values()), "Q2 and Q3 read the reproduction's published aggregates "
                  "(--docs: the folder holding reproduction/)")
    # what it writes, checked before the analysis (issue 62: a late failure after the work)
    for target in (out / "claims.md", figs / "full_contact.png"):
        check_writable(target, "regenerate's output")
    rep = _reproduction(docs)
    figs.mkdir(parents=True, exist_ok=True)
    large = _optional(data, "representative-2L.nc")
    extra, big = (read_dataset(data / name, stage="aggregate") if (data / name).exists() else None
                  for name in ("kappa-alpha.nc", "kappa-alpha-4096.nc"))
    ds = an.one_pair(read_dataset(data / "full-contact.nc", stage="aggregate"))
    cel = read_dataset(data / "full-contact-cel.nc", stage="fit")
    curve = an.pooled_curve(ds)
    curves = {float(h): an.gap_and_stiffness(ds, float(h)) for h in ds["H"].values}
    modes = {}
    for name in MODE_CELLS:
        cells = _optional(data, name)
        if cells is not None:
            modes[name] = {float(h): an.gap_and_stiffness(cells, float(h), spectra=("expected",))
                           for h in cells["H"].values}
    wrap, wrap_fine = (_optional(data, name) for name in ("percolation.nc", "percolation-2048.nc"))
    perc = (an.percolation_definitions(wrap) if wrap is not None else
            an.percolation_threshold(an.percolation_brackets(ds)))
    perc_fine = an.percolation_definitions(wrap_fine) if wrap_fine is not None else None
    save_figure(fg.area_figure(curve, an.cel_validity(curve, an.cel_constants(cel)), an.full_contact_onset(ds)),
                figs / "full_contact.png")
    save_figure(fg.gap_stiffness_figure(curves), figs / "gap_stiffness.png")
    save_figure(fg.pressure_figure(an.pressure_distributions(ds)), figs / "pressure_distribution.png")
    save_figure(fg.cluster_figure(an.cluster_counts(ds)), figs / "clusters.png")
    save_figure(fg.alpha_figure(kp.alpha_points(rep["grid"], 32.0), kp.alpha_points(kp.corrected(rep["grid"]), 32.0),
                                *((kp.alpha_points(extra, 64.0), kp.alpha_points(kp.corrected(extra), 64.0))
                                  if extra is not None else (None, None)),
                                *((kp.alpha_points(big, 128.0), kp.alpha_points(kp.corrected(big), 128.0))
                                  if big is not None else (None, None)), bends=_bends(rep["grid"], extra, big)),
                figs / "kappa_alpha.png")
    if large is not None:
        save_figure(fg.cell_figure(rep["small"], large), figs / "cell_size.png")
    rows = (full_contact_rows(ds, cel) + alpha_rows(rep["grid"]) + [trend_row(rep["grid"], extra),
                                                                     range_row(rep["grid"], extra, big)]
            + cell_rows(rep["small"], large) + users_rows(ds, curves, perc, perc_fine, modes))
    write_text_atomic(out / "claims.md", markdown_table(rows))


def publish(results: Path, cells: Path, alpha: Path, out: Path, more: dict[str, Path] | None = None) -> None:
    """Copy the runs' files (:data:`DATA_FILES`) into ``out/data``, then :func:`regenerate`.

    ``results`` is the full-contact run (``results/full-contact``), ``cells`` the 2L one
    (``results/representative-2L``), ``alpha`` the kappa-alpha one (``results/kappa-alpha``);
    ``more`` maps a file of :data:`MORE_RUNS` to its run (``{"percolation.nc": results/percolation}``).
    """
    data = out / "data"
    more = dict(more or {})
    unknown = sorted(set(more) - set(MORE_RUNS))
    if unknown:
        raise ValueError(f"--run takes FILE=RUN with FILE one of {', '.join(MORE_RUNS)}; got {', '.join(unknown)}")
    runs = {"representative-2L.nc": cells, "kappa-alpha.nc": alpha, **more}
    for name, source in DATA_FILES.items():
        if name not in OPTIONAL or name in more:
            require_files(runs.get(name, results), [source], "give the finished run's results folder")
    data.mkdir(parents=True, exist_ok=True)
    for name, source in DATA_FILES.items():
        if name in MORE_RUNS and name not in more:
            continue  # published separately, or pending
        origin = runs.get(name, results) / source
        if origin.exists() or name not in OPTIONAL:  # a run still going: its rows read "pending"
            shutil.copyfile(origin, data / name)
    regenerate(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(prog="python -m roughcontact.studies.open_questions", description=__doc__)
    sub = ap.add_subparsers(dest="command", required=True)
    reg = sub.add_parser("regenerate", help="figures and claims.md from OUT/data")
    reg.add_argument("out", type=Path)
    reg.add_argument("--docs", type=Path, help="the folder holding reproduction/ (default: OUT's parent)")
    pub = sub.add_parser("publish", help="copy the full-contact and 2L runs' files, then regenerate")
    pub.add_argument("results", type=Path, help="results/full-contact")
    pub.add_argument("cells", type=Path, help="results/representative-2L")
    pub.add_argument("alpha", type=Path, help="results/kappa-alpha")
    pub.add_argument("out", type=Path)
    pub.add_argument("--run", action="append", default=[], metavar="FILE=RUN",
                     help=f"a further finished run, FILE one of {', '.join(MORE_RUNS)} (repeatable)")
    args = ap.parse_args(argv)
    with input_errors(ap):
        if args.command == "publish":
            more = dict(item.split("=", 1) for item in args.run)
            publish(args.results, args.cells, args.alpha, args.out, {k: Path(v) for k, v in more.items()})
        else:
            regenerate(args.out, args.docs)

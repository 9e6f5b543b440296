"""The paper's claims measured on a run: numbers, verdicts and figures for docs/reproduction/.

Pure functions over the aggregates (:func:`claims`), and the two commands of the
reproduction (``python -m roughcontact.studies.reproduction``):

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
import json
import shutil
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

from ..core.cli import input_errors, require_files, require_folder
from ..core.files import write_text_atomic
from ..figures.load_curves import PAPER_ALPHA
from ..figures.registry import FIGURES
from ..figures.style import save_figure
from ..pipeline.io import read_dataset
from ..theory.asperity import asperity_area
from .representativity_claims import representativity_claims
from .verdicts import judged_row as _judged, row as _row

#: The constants the paper states for lambda_l = L/16, lambda_s = L/32 (its Figs. 3-4).
PAPER_KAPPA = 1.145 * np.sqrt(2 * np.pi)


#: The paper's CEL constants per (k_l, k_s) as (low, high) ranges: ``value +- error`` for
#: lambda_s = L/32 (its text), the caption of its Fig. 3b for lambda_s = L/128 (kappa and mu
#: without an error, beta in [1.120, 1.172] as printed).
PAPER_CEL = {
    (16.0, 32.0): {"kappa": (PAPER_KAPPA - 0.002 * np.sqrt(2 * np.pi), PAPER_KAPPA + 0.002 * np.sqrt(2 * np.pi)),
                   "mu": (0.53, 0.57), "beta": (0.205, 0.215)},
    (16.0, 128.0): {"kappa": (PAPER_KAPPA, PAPER_KAPPA), "mu": (0.56, 0.56), "beta": (1.120, 1.172)},
}


#: Areas at which kappa's decrease with A/A0 is tested (the paper's window, up to ~10 %).
KAPPA_AREAS = (0.01, 0.02, 0.05, 0.1)


#: Area fraction at which kappa is compared across cases (inside the paper's fit window).
KAPPA_AREA = 0.05


#: Files of a published reproduction, relative to its data folder.
DATA_FILES = ("representativity.nc", "contact.nc", "cel.nc", "cel.csv")


def kappa_at(con: xr.Dataset, area: float = KAPPA_AREA) -> xr.DataArray:
    """kappa of every case at ``A/A0 = area``, log-linear in A between load steps.

    ``con`` is a contact aggregate (``kappa`` and ``area_fraction`` over
    ``k_l, k_s, H, seed, step``); cases that never reach ``area`` give NaN.
    Returns dims ``(k_l, k_s, H, seed)`` [1].
    """
    def interp(a, k):
        ok = np.isfinite(a) & np.isfinite(k) & (a > 0)
        if ok.sum() < 2 or not a[ok].min() <= area <= a[ok].max():
            return np.nan
        order = np.argsort(a[ok])
        return float(np.interp(np.log(area), np.log(a[ok][order]), k[ok][order]))

    return xr.apply_ufunc(interp, con["area_fraction"], con["kappa"], input_core_dims=[["step"], ["step"]],
                          vectorize=True)


def _sel(da: xr.DataArray, **coords) -> xr.DataArray:
    return da.sel({k: float(v) for k, v in coords.items()})


def _pending(claim: str, paper: str, needs: str) -> dict:
    return _row(claim, paper, f"not yet run: needs {needs}", "pending", "—")


def _full_cells(con: xr.Dataset) -> xr.DataArray:
    """True at each ``(k_l, k_s, H)`` whose every seed is present (all True without ``case_present``)."""
    if "case_present" not in con:
        return xr.ones_like(con["kappa"].isel(step=0, seed=0), dtype=bool)
    return con["case_present"].all("seed")


def _seed_stats(kap: xr.DataArray, con: xr.Dataset) -> tuple[xr.DataArray, xr.DataArray]:
    """Seed mean and s.d. (ddof=1) of ``kap``, NaN where a seed is missing.

    A mean over some of the seeds is another estimator than the mean over all of them, so
    a partly run (k_l, k_s, H) cell is left out rather than compared with complete ones.
    """
    full = _full_cells(con)
    return kap.mean("seed").where(full), kap.std("seed", ddof=1).where(full)


def _complete_along(da: xr.DataArray, dim: str) -> xr.DataArray:
    """``da`` where every value along ``dim`` is finite, NaN elsewhere.

    Averages compared along ``dim`` (kappa per k_l, say) then run over the same cells of
    the other parameters, so a grid hole cannot masquerade as a trend.
    """
    return da.where(da.notnull().all(dim))


def _coverage_note(con: xr.Dataset) -> str:
    """'' for a complete grid, else how much of it is present and what the comparisons use."""
    if "case_present" not in con or bool(con["case_present"].all()):
        return ""
    present = con["case_present"]
    return (f" [incomplete grid: {int(present.sum())} of {present.size} cases; cells missing a seed are left out "
            "and each comparison uses the cells complete along its parameter]")


KAPPA_CLAIMS = {
    "H": ("κ(A/A0) independent of H for representative smooth surfaces, H-dependent otherwise",
          "independent at λ_l = L/16, λ_s = L/32; higher H, smaller κ at λ_l = L"),
    "scatter": ("seed scatter falls with k_l and rises with H", "falls with k_l, rises with H"),
    "k_l": ("κ rises as λ_l falls (k_l rises)", "rises"),
}


def kappa_claims(con: xr.Dataset) -> list[dict]:
    """H-independence, scatter, kappa against lambda_l and the asymptotes (the paper's Fig. 3)."""
    if con.sizes["k_l"] < 2 or con.sizes["H"] < 2:
        needs = "at least two k_l and two H in the contact aggregate"
        return [_pending(*KAPPA_CLAIMS["H"], needs), _pending(H_DIRECTION_CLAIM, "smaller", needs),
                _pending(*KAPPA_CLAIMS["scatter"], needs), _pending(*KAPPA_CLAIMS["k_l"], needs)
                ] + _asymptote_claim(con)
    kap = kappa_at(con)
    mean, std = _seed_stats(kap, con)
    sem = std / np.sqrt(kap.notnull().sum("seed"))
    kl_max, ks_min = float(mean.k_l.max()), float(mean.k_s.min())
    return [_h_spread_row(mean), _h_direction_row(_complete_along(mean, "H"), kl_max, ks_min),
            _scatter_row(std / mean), _kl_row(mean, sem)] + _asymptote_claim(con)


def _h_spread_row(mean: xr.DataArray) -> dict:
    """kappa(0.05)'s spread over H at the representative smooth family against the least representative one."""
    kl_max, kl_min, ks_min = float(mean.k_l.max()), float(mean.k_l.min()), float(mean.k_s.min())
    full = _complete_along(mean, "H")
    h_spread = (full.max("H") - full.min("H")) / full.mean("H")
    rep_spread, nonrep_spread = float(_sel(h_spread, k_l=kl_max, k_s=ks_min)), float(_sel(h_spread, k_l=kl_min,
                                                                                             k_s=ks_min))
    if not (np.isfinite(rep_spread) and np.isfinite(nonrep_spread)):
        return _pending(*KAPPA_CLAIMS["H"], f"every H with every seed at (k_l, k_s) = ({kl_max:g}, {ks_min:g}) and "
                        f"({kl_min:g}, {ks_min:g})")
    return _judged(
        *KAPPA_CLAIMS["H"],
        f"spread of κ(A/A0={KAPPA_AREA}) over H: {100 * rep_spread:.1f} % at (k_l, k_s) = ({kl_max:g}, "
        f"{ks_min:g}), {100 * nonrep_spread:.1f} % at ({kl_min:g}, {ks_min:g})")


def _scatter_row(cv: xr.DataArray) -> dict:
    """The seed coefficient of variation of kappa(0.05) against k_l and against H."""
    by_kl = _complete_along(cv, "k_l").mean(["k_s"]).mean("H")
    by_h = _complete_along(cv, "H").mean(["k_s"]).mean("k_l")
    if by_kl.isnull().any() or by_h.isnull().any():
        return _pending(*KAPPA_CLAIMS["scatter"], "a (k_s, H) cell run for every k_l and a (k_l, k_s) cell "
                        "run for every H, with every seed")
    return _judged(
        *KAPPA_CLAIMS["scatter"],
        "s.d./mean of κ(0.05) over seeds: " + ", ".join(f"{100 * float(v):.1f} % (k_l={float(k):g})"
                                                         for k, v in zip(by_kl.k_l.values, by_kl.values,
                                                                         strict=True))
        + "; " + ", ".join(f"{100 * float(v):.1f} % (H={float(h):g})"
                           for h, v in zip(by_h.H.values, by_h.values, strict=True)))


def _kl_row(mean: xr.DataArray, sem: xr.DataArray) -> dict:
    """The seed-, H- and k_s-mean kappa(0.05) against k_l, with its standard error.

    ``mean`` and ``sem`` (standard error of each cell's seed mean) have dims
    ``(k_l, k_s, H)``. Cells are independent surfaces, so the error of an average over
    ``m`` cells is sqrt(sum sem^2) / m. A fall between neighbouring k_l inside two standard
    errors is a plateau within the seed scatter, not a contradiction.
    """
    full = _complete_along(mean, "k_l")
    kl_mean = full.mean(["k_s", "H"])
    if kl_mean.isnull().any():
        return _pending(*KAPPA_CLAIMS["k_l"], "a (k_s, H) cell run for every k_l with every seed")
    cells = full.notnull().sum(["k_s", "H"])
    kl_sem = np.sqrt((sem**2).where(full.notnull()).sum(["k_s", "H"])) / cells
    k, e = kl_mean.values, kl_sem.values
    return _judged(
        *KAPPA_CLAIMS["k_l"],
        "κ(0.05): " + ", ".join(f"{float(v):.3f} ± {float(d):.3f} (k_l={float(kl):g})"
                                for kl, v, d in zip(kl_mean.k_l.values, k, e, strict=True)))


H_DIRECTION_CLAIM = ("higher H gives smaller κ for non-representative (λ_l > L/16) or rough (λ_s < 32 Δx) "
                     "surfaces")


def _h_direction_row(mean: xr.DataArray, kl_rep: float, ks_rep: float) -> dict:
    """Every (k_l, k_s) family but the representative smooth one: kappa(0.05) against H."""
    ends, monotone, names = [], [], []
    for kl in mean.k_l.values:
        for ks in mean.k_s.values:
            if (kl, ks) == (kl_rep, ks_rep):
                continue
            k = mean.sel(k_l=kl, k_s=ks).dropna("H").values
            if k.size < 2:
                continue
            ends.append(k[-1] < k[0])
            monotone.append(bool(np.all(np.diff(k) < 0)))
            names.append(f"({kl:g}, {ks:g}): {k[0]:.3f} → {k[-1]:.3f}")
    if not ends:
        return _pending(H_DIRECTION_CLAIM, "smaller",
                        "a (k_l, k_s) family besides the representative one, run for every H with every seed")
    return _judged(
        H_DIRECTION_CLAIM, "smaller",
        "seed-mean κ(A/A0 = 0.05) from the smallest to the largest H per (k_l, k_s): " + "; ".join(names)
        + f"; falls in {sum(ends)} of {len(ends)} families, monotonically in {sum(monotone)}")


def _kappa_by_area(con: xr.Dataset) -> xr.DataArray:
    """Seed-mean kappa at each of :data:`KAPPA_AREAS`: dims ``(area, k_l, k_s, H)`` [1]."""
    return xr.concat([_seed_stats(kappa_at(con, a), con)[0] for a in KAPPA_AREAS], dim="area")


def _asymptote_claim(con: xr.Dataset) -> list[dict]:
    """kappa above sqrt(2 pi) anywhere in the fit window, for some (k_l, k_s, H)."""
    bgt = np.sqrt(2 * np.pi)
    by_area = _kappa_by_area(con)
    peak, low = by_area.max("area"), by_area.min("area")
    frac_above = float((peak > bgt).where(peak.notnull()).mean())
    return [_judged(
        "κ is not confined between the Persson (√(8/π) ≈ 1.60) and BGT (√(2π) ≈ 2.51) asymptotes",
        "not confined", f"seed-mean κ from {float(low.min()):.3f} to {float(peak.max()):.3f} over A/A0 = "
        f"0.01–0.1; above √(2π) somewhere in that range for {100 * frac_above:.0f} % of the (k_l, k_s, H) points")]


def _cel_text(name: str, v: float, lo: float, hi: float, constrained: bool) -> str:
    f, scale = (1 / np.sqrt(2 * np.pi), "·√(2π)") if name == "kappa" else (1.0, "")
    return (f"{v * f:.3f}{scale}, 95 % bootstrap interval [{lo * f:.3f}, {hi * f:.3f}]"
            + ("" if constrained else " (not constrained by the data)"))


def _paper_text(name: str, lo: float, hi: float) -> str:
    f, scale = (1 / np.sqrt(2 * np.pi), "·√(2π)") if name == "kappa" else (1.0, "")
    mid, half = (lo + hi) / 2 * f, (hi - lo) / 2 * f
    if half == 0:
        return f"{mid:.3f}{scale}"
    return f"({mid:.3f} ± {half:.3f}){scale}" if scale else f"{mid:.3f} ± {half:.3f}"


SYMBOL = {"kappa": "κ", "mu": "μ", "beta": "β"}


def cel_claims(fit: xr.Dataset, con: xr.Dataset) -> list[dict]:
    """kappa, mu and beta at (16, 32) one row each, the CEL at (16, 128) in one row; A/A0 at the final load."""
    rows = []
    point = _cel_point(fit, 16.0, 32.0)
    for name, (plo, phi) in PAPER_CEL[(16.0, 32.0)].items():
        claim = f"{name} = paper value (λ_l = L/16, λ_s = L/32, pooled H)"
        if point is None:
            rows.append(_pending(claim, _paper_text(name, plo, phi), "the fit at k_l = 16, k_s = 32"))
            continue
        v, lo, hi, ok = (float(point[k].sel(constant=name)) for k in ("value", "ci_low", "ci_high", "constrained"))
        rows.append(_judged(claim, _paper_text(name, plo, phi), _cel_text(name, v, lo, hi, bool(ok))))
    rows.append(_rough_cel_row(fit))
    final = con["area_fraction"].isel(step=-1).where(con["case_present"])
    rows.append(_judged(
        "A/A0 ≈ 10 % at the final load", "≈ 10 %",
        f"{100 * float(final.mean()):.1f} % (range {100 * float(final.min()):.1f}–{100 * float(final.max()):.1f} %)"
        f" at p0/E* = {float(con['pressure'].isel(step=-1).max()) / float(con.attrs.get('e_star', 1.0)):.4g}"))
    return rows


def _cel_point(fit: xr.Dataset, k_l: float, k_s: float) -> xr.Dataset | None:
    """The pooled, paper-route fit at ``(k_l, k_s)``, or None when the fit lacks it."""
    if k_l not in fit.k_l.values or k_s not in fit.k_s.values:
        return None
    return fit.sel(k_l=k_l, k_s=k_s, H_group="pooled", estimator="paper")


def _rough_cel_row(fit: xr.Dataset) -> dict:
    """The CEL of the paper's Fig. 3b caption (lambda_l = L/16, lambda_s = L/128), three constants in one row."""
    paper = PAPER_CEL[(16.0, 128.0)]
    claim = "CEL at λ_l = L/16, λ_s = L/128 (Fig. 3b caption)"
    paper_text = ", ".join(f"{SYMBOL[n]} = {_paper_text(n, *paper[n])}" if n != "beta" else "β ∈ [1.120, 1.172]"
                           for n in paper)
    point = _cel_point(fit, 16.0, 128.0)
    if point is None:
        return _pending(claim, paper_text, "the fit at k_l = 16, k_s = 128")
    parts = []
    for name in paper:
        v, lo, hi, ok = (float(point[k].sel(constant=name)) for k in ("value", "ci_low", "ci_high", "constrained"))
        parts.append(f"{SYMBOL[name]} = {_cel_text(name, v, lo, hi, bool(ok))}")
    return _judged(claim, paper_text, "; ".join(parts))


def figure5_claims(con: xr.Dataset) -> list[dict]:
    """kappa falls with A/A0, Persson's asymptote below every result, the asperity models at lambda_l = L."""
    return [_kappa_decreasing_row(con), _persson_row(con), _asperity_row(con)]


def _kappa_decreasing_row(con: xr.Dataset) -> dict:
    by_area = _kappa_by_area(con)
    means = by_area.values.reshape(by_area.sizes["area"], -1)
    ok = np.all(np.isfinite(means), axis=0)
    falls = np.all(np.diff(means[:, ok], axis=0) < 0, axis=0)
    frac = float(falls.mean()) if falls.size else np.nan
    return _judged(
        "κ decreases with A/A0 over the observed range (up to ≈ 10 %)", "decreasing",
        f"seed-mean κ falls from A/A0 = 0.01 through 0.02, 0.05 to 0.1 for {100 * frac:.0f} % of the "
        f"{int(ok.sum())} (k_l, k_s, H) points")


def _persson_row(con: xr.Dataset) -> dict:
    kappa = con["kappa"].where(con["case_present"] & (con["area_fraction"] > 0))
    low = float(kappa.min())
    return _judged(
        "Persson's small-load asymptote (κ = √(8/π) ≈ 1.60) lies below all results", "below all",
        f"smallest κ of any case at any load step: {low:.3f}")


def _asperity_row(con: xr.Dataset) -> dict:
    """BGT and Greenwood (alpha = 2) inside the seed scatter of lambda_l = L, H >= 0.5 (Fig. 5 caption)."""
    claim = ("BGT and Greenwood (α = 2) lie in the confidence interval of the non-representative "
             "λ_l = L results with H ≳ 0.5")
    hs = [h for h in con.H.values if h >= 0.5]
    if 1.0 not in con.k_l.values or not hs:
        return _pending(claim, "inside", "k_l = 1 and some H ≥ 0.5 in the contact aggregate")
    sub = con.sel(k_l=1.0, H=hs)
    area = sub["area_fraction"].where(sub["case_present"])
    mean, sd = _seed_stats(area, sub)
    p0 = sub["pressure"].where(sub["case_present"]).mean("seed")
    hp, e_star = float(sub["rms_slope"].where(sub["case_present"]).mean()), float(con.attrs.get("e_star", 1.0))
    inside = {}
    loaded = np.isfinite(p0)  # a (k_s, H) family without any present case has no loads
    for model in ("bgt", "greenwood"):
        theory = xr.apply_ufunc(lambda p, m=model: asperity_area(p, alpha=PAPER_ALPHA, rms_slope=hp,
                                                                 e_star=e_star, model=m), p0.where(loaded, 0.0))
        theory = theory.where(loaded)
        within = (abs(theory - mean) <= 1.96 * sd).where(np.isfinite(mean) & np.isfinite(sd))
        inside[model] = float(within.mean())
    return _judged(
        claim, "inside",
        f"load steps inside seed mean ± 1.96 s.d. (k_l = 1, all k_s, H ≥ 0.5): BGT {100 * inside['bgt']:.0f} %, "
        f"Greenwood {100 * inside['greenwood']:.0f} %")


def claims(rep: xr.Dataset, con: xr.Dataset, fit: xr.Dataset) -> list[dict]:
    """Every claim row: ``claim, paper, ours, verdict, test``.

    On a partly run contact grid every contact row that is not pending says so in ``ours``
    (how many cases it had); rows whose comparison lacks the cells it needs are pending.
    """
    contact = kappa_claims(con) + figure5_claims(con) + cel_claims(fit, con)
    note = _coverage_note(con)
    for row in contact:
        if row["verdict"] != "pending":
            row["ours"] += note
    return representativity_claims(rep) + contact


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

    from ..pipeline.datasets import surface_dataset
    from ..pipeline.io import write_dataset
    from ..surfaces.synthetic import generate_surface

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
    require_folder(out, "the publication folder, e.g. docs/reproduction")
    require_files(data, ["representativity.nc", "contact.nc", "cel.nc"], "regenerate reads the published data "
                  "in OUT/data (publish a run there first)")
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
    con = contact_results or results
    sources = {"representativity.nc": results / "aggregate" / "representativity.nc",
               "contact.nc": con / "aggregate" / "contact.nc",
               "cel.nc": con / "fit" / "cel.nc", "cel.csv": con / "fit" / "cel.csv"}
    for src in sources.values():
        if not src.is_file():
            raise FileNotFoundError(f"publish: {src} is missing; run the scene first "
                                    "(snakemake -j2 --config scene=reproduction)")
    data.mkdir(parents=True, exist_ok=True)
    for name, src in sources.items():
        shutil.copy(src, data / name)
    regenerate(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(prog="python -m roughcontact.studies.reproduction", description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("publish", help="copy a run's aggregates into OUT/data, then regenerate")
    p.add_argument("results", type=Path, help="results/{scene} of a finished run")
    p.add_argument("out", type=Path, help="publication folder, e.g. docs/reproduction")
    p.add_argument("--contact-from", type=Path, default=None,
                   help="results/{scene} to take the contact aggregate and fit from instead")
    r = sub.add_parser("regenerate", help="figures and claim table from OUT/data (seconds, no solve)")
    r.add_argument("out", type=Path, help="publication folder, e.g. docs/reproduction")
    args = ap.parse_args(argv)
    with input_errors(ap):
        if args.command == "publish":
            publish(args.results, args.out, args.contact_from)
        else:
            regenerate(args.out)


if __name__ == "__main__":
    main()

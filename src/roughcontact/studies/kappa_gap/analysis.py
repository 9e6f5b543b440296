"""The κ gap's analysis: how far each candidate cause moves κ(A/A0) at the paper's representative point.

At λ_l = L/16, λ_s = L/32 (k_l = 16, k_s = 32) our κ is below Yastrebov et al.'s (2012).
This module measures, on those surfaces, what four differences between the two studies do
to κ(A/A0) = E* h' A / (A0 p0) at A/A0 = 0.01, 0.02, 0.05, 0.1 (:data:`TARGET_AREAS`) and
to a one-constant CEL fit (μ, β held at the paper's values, :func:`fit_kappa`):

1. the solver: Stanley & Kato's displacement iteration stopped by a rule of its kind
   (:mod:`roughcontact.solver.reference.stanley_kato`) against ours, on the same surfaces and loads;
2. what counts as contact: ``p > 0`` (ours), ``gap < t s`` (``s`` the rms height) for each
   threshold ``t``, and the perimeter-corrected area A_pix − c P Δx
   (:func:`roughcontact.theory.perimeter.perimeter_corrected_area`);
3. the continuum limit: the same continuous surfaces at several N, pixel-counted and
   corrected, Richardson-extrapolated per surface (:func:`richardson`);
4. conventions: the rms slope from finite differences against the spectral one (κ is
   proportional to h'), and the paper's printed final load p0/E* = 0.05 against ours, 0.005.

A study is a set of *variants* (config ``kappa_gap.variants``), each a setting (N, solver,
load schedule, seeds) with a *role*: ``baseline`` (definitions and slopes), ``resolution``
(the continuum series), ``solver`` (Stanley & Kato and the main solver at its N) and
``load``. Each job solves one surface of one variant (:func:`solve_case`) and records, per
load step, every area definition; :func:`summarise` pairs the variants surface by surface;
:func:`markdown` writes ``kappa-gap.md``. Uncertainties are standard errors over surfaces
of paired differences (the same surface under both settings), so they measure the
candidate's effect, not the seed scatter of κ itself.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr
from scipy.optimize import minimize_scalar

from ...analysis.fit.estimators import PAPER_CEL
from .cases import TARGET_AREAS, area_variable, definitions, describe


def kappa_at_areas(area: np.ndarray, p0: np.ndarray, rms_slope: float, areas=TARGET_AREAS) -> np.ndarray:
    """κ = h' A/(A0 p0) (E* = 1) at each target area, linear in log A between steps; NaN outside."""
    a, p = np.asarray(area, float), np.asarray(p0, float)
    ok = np.isfinite(a) & (a > 0) & (p > 0)
    if ok.sum() < 2:
        return np.full(len(areas), np.nan)
    order = np.argsort(a[ok])
    la, lk = np.log(a[ok][order]), np.log(rms_slope * a[ok][order] / p[ok][order])
    out = np.interp(np.log(areas), la, lk, left=np.nan, right=np.nan)
    return np.exp(out)


def paper_kappa(areas=TARGET_AREAS) -> np.ndarray:
    """κ of the paper's CEL (κ = 1.145 √(2π), μ = 0.55, β = 0.21) at A/A0 = ``areas``."""
    kappa, mu, beta = (PAPER_CEL[c][0] for c in ("kappa", "mu", "beta"))
    a = np.asarray(areas, float)
    # A = (β + (κ x)^(μ-1))^(1/(μ-1)) solved for x; κ_eff = A / x.
    x = (a ** (mu - 1.0) - beta) ** (1.0 / (mu - 1.0)) / kappa
    return a / x


def fit_kappa(area: np.ndarray, p0: np.ndarray, rms_slope: np.ndarray, window=(0.01, 0.11)) -> float:
    """κ of the CEL with μ, β fixed at the paper's values, least squares in log A over the window.

    ``area``, ``p0`` (E* = 1): ``(n_cases, n_steps)``; ``rms_slope``: ``(n_cases,)``. One
    free constant, so the fit is well conditioned where the three-constant one is not.
    """
    mu, beta = PAPER_CEL["mu"][0], PAPER_CEL["beta"][0]
    a = np.asarray(area, float)
    x = np.asarray(p0, float) / np.asarray(rms_slope, float)[:, None]
    sel = np.isfinite(a) & (a >= window[0]) & (a <= window[1])
    la, lx = np.log(a[sel]), np.log(x[sel])

    def cost(log_kappa):
        model = np.log((beta + np.exp((mu - 1.0) * (log_kappa + lx))) ** (1.0 / (mu - 1.0)))
        return float(np.sum((model - la) ** 2))

    res = minimize_scalar(cost, bounds=(np.log(0.5), np.log(10.0)), method="bounded",
                          options={"xatol": 1e-10})
    return float(np.exp(res.x))


def richardson(values: np.ndarray, ratio: float = 2.0) -> tuple[float, float]:
    """Extrapolated limit and order from the last three values of a series refined by ``ratio``.

    ``values`` at N, ratio N, ratio² N, ... Returns ``(limit, order)``; the order is NaN
    (and the limit the finest value) when the differences do not shrink monotonically.
    """
    v = np.asarray(values, float)[-3:]
    d1, d2 = v[1] - v[0], v[2] - v[1]
    if len(v) < 3 or d1 == 0 or d2 / d1 <= 0 or abs(d2) >= abs(d1):
        return float(v[-1]), float("nan")
    order = math.log(d1 / d2) / math.log(ratio)
    return float(v[2] + d2 / (ratio**order - 1.0)), order


def collect(cases: Mapping[str, Sequence[xr.Dataset]], block: Mapping) -> xr.Dataset:
    """One Dataset over ``(variant, case, step)`` from each variant's case Datasets.

    ``cases[label]`` holds the variant's per-case Datasets (:func:`solve_case`, with attrs
    ``H`` and ``seed``); missing cases and steps are NaN (``allow_nan``). ``block`` is the
    study's config block: variant settings become coordinates along ``variant``, the
    surfaces' parameters global attributes. No timing: the Dataset is a function of the cases
    alone, so a rerun writes the same bytes (a job's wall time is in Snakemake's benchmark file,
    ``python -m roughcontact.pipeline.runcost``).
    """
    variants = block["variants"]
    labels = list(variants)
    def name(ds):
        return f"H{ds.attrs['H']}_s{int(ds.attrs['seed'])}"

    keyed = {(float(ds.attrs["H"]), int(ds.attrs["seed"])): name(ds) for label in labels for ds in cases[label]}
    names = [keyed[k] for k in sorted(keyed)]
    n_steps = max(ds.sizes["step"] for label in labels for ds in cases[label])
    keys = [k for k in next(iter(cases[labels[0]])).data_vars]
    out = {k: np.full((len(labels), len(names), n_steps), np.nan) for k in keys}
    slopes = {k: np.full((len(labels), len(names)), np.nan) for k in ("rms_slope_spectral", "rms_slope_discrete",
                                                                      "rms_height")}
    for i, label in enumerate(labels):
        for ds in cases[label]:
            j = names.index(name(ds))
            for k in keys:
                out[k][i, j, : ds.sizes["step"]] = ds[k].values
            for k in slopes:
                slopes[k][i, j] = ds.attrs[k]
    first = next(iter(cases[labels[0]]))
    res = xr.Dataset(coords={
        "variant": ("variant", labels, {"units": "1", "long_name": "setting of the kappa-gap study"}),
        "case": ("case", names, {"units": "1", "long_name": "surface: Hurst exponent and seed"}),
        "step": ("step", np.arange(1, n_steps + 1), {"units": "1", "long_name": "load step"}),
    })
    for k in keys:
        res[k] = (("variant", "case", "step"), out[k], {**first[k].attrs, "allow_nan": 1})
    res.attrs.update(k_l=block["k_l"], k_s=block["k_s"], H=", ".join(block["H"]),
                     gap_thresholds=", ".join(block["gap_thresholds"]),
                     rms_slope=float(block["surface"]["rms_slope"]))
    for k, v in slopes.items():
        what = {"rms_slope_spectral": "rms slope from the spectrum", "rms_slope_discrete":
                "rms slope from central differences", "rms_height": "rms height"}[k]
        res[k] = (("variant", "case"), v, {"units": "1", "long_name": what, "allow_nan": 1})
    kinds = {"role": str, "method": str, "N": int, "tol": str, "p_max": float, "n_steps": int, "schedule": str}
    for key, kind in kinds.items():
        res.coords[f"variant_{key}"] = ("variant", [kind(variants[label][key]) for label in labels],
                                        {"units": "1", "long_name": f"variant setting {key}"})
    return res


def _kappa(data: xr.Dataset, label: str, definition: str, slope: str = "spectral", load: str = "p0") -> np.ndarray:
    """κ at :data:`TARGET_AREAS` for every case of a variant: ``(n_case, n_area)``, NaN where not reached."""
    v = data.sel(variant=label)
    area, p0 = v[area_variable(definition)].values, v[load].values
    h = v[f"rms_slope_{slope}"].values
    return np.array([kappa_at_areas(area[i], p0[i], h[i]) if np.isfinite(h[i]) else np.full(len(TARGET_AREAS), np.nan)
                     for i in range(area.shape[0])])


def _paired(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Mean and standard error over cases of a/b − 1, per area, on the cases where both exist there.

    The count returned is the largest over areas (a load schedule may miss the smallest areas).
    """
    r = a / b - 1.0
    ok = np.isfinite(r)
    counts = ok.sum(axis=0)
    mean = np.array([r[ok[:, j], j].mean() if counts[j] else np.nan for j in range(r.shape[1])])
    se = np.array([r[ok[:, j], j].std(ddof=1) / math.sqrt(counts[j]) if counts[j] > 1 else np.nan
                   for j in range(r.shape[1])])
    return mean, se, int(counts.max())


def _role(data: xr.Dataset, role: str) -> list[str]:
    return [str(v) for v in data.variant.values if str(data.variant_role.sel(variant=v).item()) == role]


def _fit(data: xr.Dataset, label: str, definition: str) -> float:
    v = data.sel(variant=label)
    ok = np.isfinite(v["rms_slope_spectral"].values)
    return fit_kappa(v[area_variable(definition)].values[ok], v["p0"].values[ok], v["rms_slope_spectral"].values[ok])


def pct(m: float, se: float) -> str:
    """A relative shift and its standard error as percentages, ``'+1.23 ± 0.45'`` (a dash when not finite)."""
    return "—" if not np.isfinite(m) else f"{100 * m:+.2f} ± {100 * se:.2f}" if np.isfinite(se) else f"{100 * m:+.2f}"


def closes(shift: np.ndarray, se: np.ndarray, needed: np.ndarray, needed_se: np.ndarray) -> str:
    """The printed rule (:data:`CLOSES_RULE`) applied to one candidate's shifts.

    ``needed``: the shift that would bring our κ onto the paper's law (positive: the
    paper's κ is higher), per target area, with its standard error ``needed_se``.
    """
    if np.all(np.abs(shift - needed) <= 2 * np.hypot(se, needed_se)):
        return "**yes**"
    if np.any((shift > 2 * se) & (shift >= MATERIAL * needed) & (needed > 0)):
        return "**part**"
    return "**no**"


#: Least share of the gap a candidate must close somewhere to count as part of the explanation.
MATERIAL = 0.1


CLOSES_RULE = ("*closes the gap?* **yes** when at every A/A0 the shift equals the gap's size (the shift that "
               "would put our κ on the paper's law) within two combined standard errors; **part** when at "
               "some A/A0 it raises κ toward the paper by more than two standard errors and by at least "
               f"{100 * MATERIAL:.0f} % of the gap there, without closing it everywhere; **no** otherwise (it leaves "
               "κ where it is, lowers it, or moves it by a negligible share)")


def _continuum(data: xr.Dataset, definition: str, ref_n: int, n_boot: int = 1000, seed: int = 2012) -> dict:
    """κ per N and the Richardson limit over the resolution variants' shared cases.

    ``ratio``: the limit over the pixel-counted κ of the series at N = ``ref_n`` (the
    baseline's N; the series' coarsest N if it lacks it) on the same surfaces, − 1, with
    its bootstrap standard error: how far the continuum lies from that grid's answer.
    """
    labels = sorted(_role(data, "resolution"), key=lambda v: int(data.variant_N.sel(variant=v)))
    ns = [int(data.variant_N.sel(variant=v)) for v in labels]
    ks = np.stack([_kappa(data, label, definition) for label in labels])        # (n_N, case, area)
    ref = np.stack([_kappa(data, label, "pressure") for label in labels])[ns.index(ref_n) if ref_n in ns else 0]
    shared = np.all(np.isfinite(ks[-3:]), axis=(0, 2)) & np.all(np.isfinite(ref), axis=1)
    k3, kr = ks[-3:, shared], ref[shared]                                         # (3, case, area), (case, area)
    n_area = len(TARGET_AREAS)

    def estimate(pick):
        lim = np.array([richardson(k3[:, pick, a].mean(axis=1)) for a in range(n_area)])
        return lim[:, 0], lim[:, 1], lim[:, 0] / kr[pick].mean(axis=0) - 1.0

    if not shared.any():
        nan = np.full(n_area, np.nan)
        return {"labels": labels, "N": ns, "kappa": ks, "n_shared": 0, "limit": nan, "limit_se": nan,
                "order": nan, "ratio": nan, "ratio_se": nan}
    limit, order, ratio = estimate(np.arange(k3.shape[1]))
    rng = np.random.default_rng(seed)
    boot = [estimate(rng.integers(0, k3.shape[1], k3.shape[1])) for _ in range(n_boot)]
    return {"labels": labels, "N": ns, "kappa": ks, "n_shared": int(shared.sum()), "limit": limit,
            "limit_se": np.std([b[0] for b in boot], axis=0, ddof=1), "order": order, "ratio": ratio,
            "ratio_se": np.std([b[2] for b in boot], axis=0, ddof=1)}


def summarise(data: xr.Dataset) -> dict:
    """Every number of ``kappa-gap.md``, from a :func:`collect` Dataset."""
    base = _role(data, "baseline")[0]
    k_base = _kappa(data, base, "pressure")
    paper = paper_kappa()
    gap, gap_se, n_base = _paired(k_base, np.broadcast_to(paper, k_base.shape))
    needed = 1.0 / (1.0 + gap) - 1.0
    meta = {"k_l": data.attrs["k_l"], "k_s": data.attrs["k_s"], "H": data.attrs["H"],
            "rms_slope": float(data.attrs["rms_slope"]), "N": int(data.variant_N.sel(variant=base)),
            "p_max": float(data.variant_p_max.sel(variant=base))}
    out = {"meta": meta, "baseline": base, "n_base": n_base, "gap": gap, "gap_se": gap_se, "paper": paper,
           "kappa_base": np.nanmean(k_base, axis=0), "fit_base": _fit(data, base, "pressure"), "rows": []}

    def row(section, label, shift, se, n, fitted=float("nan")):
        out["rows"].append({"section": section, "candidate": label, "shift": shift, "se": se, "n": n,
                            "fit": fitted, "closes": closes(shift, se, needed, gap_se / (1 + gap) ** 2)})

    ref = {str(data.variant_N.sel(variant=v).item()): v for v in _role(data, "solver")
           if data.variant_method.sel(variant=v).item() == "bem"}
    for v in _role(data, "solver"):
        if data.variant_method.sel(variant=v).item() != "stanley-kato":
            continue
        r = ref[str(data.variant_N.sel(variant=v).item())]
        tol, n = data.variant_tol.sel(variant=v).item(), int(data.variant_N.sel(variant=v).item())
        for load, what in (("p0", "applied p0"), ("carried_load", "carried load")):
            row("solver", f"Stanley & Kato, stopped at tol = {tol} (N = {n}), κ from the {what}",
                *_paired(_kappa(data, v, "pressure", load=load), _kappa(data, r, "pressure")))
    for d in definitions(data.attrs["gap_thresholds"].split(", "))[1:]:
        row("definition", describe(d), *_paired(_kappa(data, base, d), k_base), _fit(data, base, d))
    for d in ("pressure", "corrected"):
        c = _continuum(data, d, meta["N"])
        out[f"continuum_{d}"] = c
        row("continuum", f"continuum limit of the {'pixel-counted' if d == 'pressure' else 'perimeter-corrected'} "
            f"area (Richardson, N = {c['N'][-3]}…{c['N'][-1]}) against pixels at N = {meta['N']}",
            c["ratio"], c["ratio_se"], c["n_shared"])
    ratio = data.sel(variant=base)["rms_slope_discrete"] / data.sel(variant=base)["rms_slope_spectral"]
    r = ratio.values[np.isfinite(ratio.values)]
    row("convention", "κ with the finite-difference h' instead of the spectral one",
        np.full(len(TARGET_AREAS), r.mean() - 1.0),
        np.full(len(TARGET_AREAS), r.std(ddof=1) / math.sqrt(r.size)), r.size)
    for v in _role(data, "load"):
        pm = float(data.variant_p_max.sel(variant=v))
        row("convention", f"30 steps to p0/E* = {pm:g} instead of 0.005",
            *_paired(_kappa(data, v, "pressure"), k_base), _fit(data, v, "pressure"))
        out.setdefault("loads", []).append(_load_reach(data, v))
    out["solver_detail"] = [_solver_detail(data, v, ref) for v in _role(data, "solver")
                            if data.variant_method.sel(variant=v).item() == "stanley-kato"]
    out["cost"] = _cost(data)
    return out


def _load_reach(data: xr.Dataset, label: str) -> dict:
    v = data.sel(variant=label)
    a = v["area_pressure"].values
    ok = np.isfinite(a[:, 0])
    last = np.array([row[np.isfinite(row)][-1] for row in a[ok]])
    inside = np.array([np.sum((row >= 0.01) & (row <= 0.11)) for row in a[ok]])
    return {"label": label, "p_max": float(data.variant_p_max.sel(variant=label)), "final_mean": last.mean(),
            "final_min": last.min(), "final_max": last.max(), "first_mean": a[ok, 0].mean(),
            "in_window": inside.mean(), "n": int(ok.sum())}


def _solver_detail(data: xr.Dataset, label: str, ref: Mapping[str, str]) -> dict:
    v = data.sel(variant=label)
    r = data.sel(variant=ref[str(data.variant_N.sel(variant=label).item())])
    err = np.abs(v["carried_load"].values / v["p0"].values - 1.0)
    ratio = v["area_pressure"].values / r["area_pressure"].values
    def per_surface(ds):
        its = ds["iterations"].values
        return float(np.nansum(its, axis=1)[np.isfinite(its[:, 0])].mean())

    return {"label": label, "tol": str(data.variant_tol.sel(variant=label).item()),
            "N": int(data.variant_N.sel(variant=label).item()),
            "iterations": per_surface(v), "ref_iterations": per_surface(r),
            "load_error_max": float(np.nanmax(err)), "stopped": bool(np.nanmin(v["stopped"].values) == 1),
            "area_ratio_min": float(np.nanmin(ratio)), "area_ratio_max": float(np.nanmax(ratio))}


def _cost(data: xr.Dataset) -> list[dict]:
    """Each variant's solver iterations (all steps of all its surfaces) and their work, iterations x N²."""
    rows = []
    for v in data.variant.values:
        its = data["iterations"].sel(variant=v).values
        solved = np.isfinite(its[:, 0])
        total = int(np.nansum(its[solved]))
        n = int(data.variant_N.sel(variant=v).item())
        cases = int(solved.sum())
        rows.append({"label": str(v), "role": str(data.variant_role.sel(variant=v).item()), "N": n,
                     "method": str(data.variant_method.sel(variant=v).item()), "cases": cases,
                     "iterations": total, "per_case": total / max(cases, 1), "node_iterations": float(total) * n * n})
    return rows

"""Numbers behind the open-questions page: pure functions over a published contact aggregate.

The aggregate is a contact scene's ``aggregate/contact.nc`` (dims ``k_l, k_s, H, seed, step``, one
``(k_l, k_s)`` pair here). Loads are reduced to ``pbar = p0 / (E* h')`` with each surface's own rms
slope ``h'``; lengths are in the scene's unit (``L = 1``). Means and standard errors are over seeds
(``sem = s.d. / sqrt(n)``), per ``H`` or pooled over ``H`` and seeds.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.special import erfc

from ...statistics.wrapping import WRAPS_BOTH, WRAPS_X, WRAPS_Y, first_wrapping
from ...surfaces.synthetic import generate_surface
from ...theory import (
    cel_area,
    mode_spectrum,
    persson_area,
    persson_mean_gap,
    persson_mean_gap_terms,
    persson_pressure_distribution,
    persson_stiffness,
    persson_stiffness_terms,
    power_law_terms,
)

#: Area fractions at which the curves are compared with the theories (interpolated in ln pbar).
AREAS = (0.01, 0.1, 0.5, 0.9)

#: Persson's gamma in the mean-separation integral (Yang & Persson 2008).
GAMMA = 0.45

#: The band of gamma the mean gap and stiffness are shown over (its published range of use).
GAMMAS = (0.4, 0.45, 0.5)

#: Persson's input spectra: the generator's expected one, or each surface's own (its FFT).
SPECTRA = ("expected", "measured")

#: The sensitivity of Persson's gap and stiffness to how w(q) is discretised (at :data:`GAMMA`, expected
#: spectrum), beside the main line's midpoint rule: the whole shell and per-mode rules
#: (:func:`~roughcontact.theory.mode_weights`) and the continuum integral over the ideal power law
#: (:func:`~roughcontact.theory.power_law_terms`).
W_SENSITIVITY = ("shell", "mode", "continuum")


def one_pair(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` without its length-1 ``k_l``, ``k_s`` dimensions (a scene of one spectrum pair)."""
    if ds.sizes.get("k_l", 1) != 1 or ds.sizes.get("k_s", 1) != 1:
        raise ValueError(f"expected one (k_l, k_s) pair, got k_l={ds['k_l'].values}, k_s={ds['k_s'].values}")
    return ds.squeeze(("k_l", "k_s"))


def reduced_load(ds: xr.Dataset) -> xr.DataArray:
    """``pbar = p0 / (E* h')`` per case and step [-]."""
    return ds["pressure"] / (float(ds.attrs["e_star"]) * ds["rms_slope"])


def seed_mean(da: xr.DataArray, dims=("seed",)) -> tuple[xr.DataArray, xr.DataArray]:
    """Mean and standard error of ``da`` over ``dims`` (NaN-aware; a single value has no error)."""
    n = da.notnull().sum(dims)
    mean = da.mean(dims)
    sem = da.std(dims, ddof=1) / np.sqrt(n)
    return mean, sem


def at_areas(area: np.ndarray, values: np.ndarray, pbar: np.ndarray, areas=AREAS) -> dict[float, tuple]:
    """``(pbar, value)`` interpolated in ``ln pbar`` where the increasing ``area`` curve crosses each of ``areas``."""
    out = {}
    lp = np.log(pbar)
    for a in areas:
        k = int(np.searchsorted(area, a))
        if k == 0 or k >= area.size:
            continue
        t = (a - area[k - 1]) / (area[k] - area[k - 1])
        out[a] = (float(np.exp(lp[k - 1] + t * (lp[k] - lp[k - 1]))),
                  float(values[k - 1] + t * (values[k] - values[k - 1])))
    return out


# ----------------------------------------------------------------------------- toward full contact
def pooled_curve(ds: xr.Dataset) -> dict[str, np.ndarray]:
    """Pooled (all H and seeds) ``pbar`` and ``A/A0`` (mean, sem) per step."""
    pbar = reduced_load(ds)
    area, sem = seed_mean(ds["area_fraction"], ("H", "seed"))
    return {"pbar": pbar.mean(("H", "seed")).values, "area": area.values, "area_sem": sem.values}


def cel_constants(cel: xr.Dataset) -> dict[str, float]:
    """The pooled-H CEL constants (the paper's estimator) of a fit file."""
    sel = cel["value"].squeeze(("k_l", "k_s"), drop=True).sel(H_group="pooled", estimator="paper")
    return {c: float(sel.sel(constant=c)) for c in ("kappa", "mu", "beta")}


def cel_full_load(constants: dict) -> float:
    """The ``pbar`` at which the CEL reaches A/A0 = 1: ``(1 - beta)^(1/(mu - 1)) / kappa`` (NaN when never)."""
    k, m, b = constants["kappa"], constants["mu"], constants["beta"]
    return float((1.0 - b) ** (1.0 / (m - 1.0)) / k) if b < 1 else float("nan")


def tolerance_crossing(area: np.ndarray, deviation: np.ndarray, rtol: float) -> tuple[float, float, float]:
    """Where ``abs(deviation)`` first exceeds ``rtol``: ``(crossing, below, above)`` in A/A0.

    ``below`` and ``above`` are the A/A0 of the last step within ``rtol`` and of the first beyond
    (they bound the crossing); ``crossing`` interpolates ``abs(deviation)`` linearly in A/A0 between
    them. No step beyond: ``(nan, last A/A0, nan)``; the first step beyond: ``(0, nan, its A/A0)``.
    """
    dev = np.abs(np.asarray(deviation, dtype=float))
    out = dev > rtol
    if not out.any():
        return float("nan"), float(area[-1]), float("nan")
    k = int(np.argmax(out))
    if k == 0:
        return 0.0, float("nan"), float(area[0])
    t = (rtol - dev[k - 1]) / (dev[k] - dev[k - 1])
    return float(area[k - 1] + t * (area[k] - area[k - 1])), float(area[k - 1]), float(area[k])


def cel_validity(curve: dict, constants: dict, rtol: float = 0.05, sensitivity: float = 0.04) -> dict:
    """Where the CEL holds: ``A_CEL / A - 1`` per step, the largest ``A/A0`` up to which it stays within ``rtol``.

    Returns ``deviation`` (per step), ``holds_up_to`` (the measured A/A0 of the last step of the
    run of steps from the first one within ``rtol``; 0 if the first is not), ``fails_at`` (the next
    step's A/A0, or NaN),
    ``crossing`` and ``crossing_sensitivity`` (:func:`tolerance_crossing` at ``rtol`` and at
    ``sensitivity``) and ``cel_full`` (the law's own ``pbar`` at A/A0 = 1, :func:`cel_full_load`).
    """
    pbar, area = curve["pbar"], curve["area"]
    pred = cel_area(pbar, rms_slope=1.0, e_star=1.0, **constants)
    dev = pred / area - 1.0
    ok = np.abs(dev) <= rtol
    run = int(np.argmin(ok)) if not ok.all() else ok.size
    return {"deviation": dev, "holds_up_to": float(area[run - 1]) if run else 0.0,
            "fails_at": float(area[run]) if run < area.size else np.nan,
            "crossing": tolerance_crossing(area, dev, rtol),
            "crossing_sensitivity": tolerance_crossing(area, dev, sensitivity),
            "rtol": rtol, "sensitivity": sensitivity,
            "cel_full": cel_full_load(constants), "prediction": pred}


def persson_deviation(curve: dict) -> np.ndarray:
    """``A_Persson / A - 1`` per step (Persson's erf curve on the pooled mean)."""
    return persson_area(curve["pbar"], rms_slope=1.0, e_star=1.0) / curve["area"] - 1.0


def full_contact_onset(ds: xr.Dataset) -> dict:
    """Cases whose steps are in full contact exactly when ``p0`` exceeds the exact full-contact load.

    ``consistent``: number of cases where ``A/A0 == 1`` at every step with ``p0 > p_fc`` and
    ``A/A0 < 1`` at every step with ``p0 < p_fc``; ``n``: cases; ``pbar_fc`` mean and sem of
    ``p_fc / (E* h')`` per H and pooled.
    """
    p_fc = ds["full_contact_pressure"]
    full = ds["area_fraction"] >= 1.0
    above = ds["pressure"] > p_fc
    consistent = (full == above).all("step")
    pbar_fc = p_fc / (float(ds.attrs["e_star"]) * ds["rms_slope"])
    mean_h, sem_h = seed_mean(pbar_fc)
    mean, sem = seed_mean(pbar_fc, ("H", "seed"))
    return {"consistent": int(consistent.sum()), "n": int(consistent.size), "pbar_fc": pbar_fc,
            "pbar_fc_H": (mean_h, sem_h), "pbar_fc_pooled": (float(mean), float(sem))}


def approach_h_spread(ds: xr.Dataset, low: float = 0.9) -> dict:
    """Does ``1 - A/A0`` near full contact depend on H? Pairwise z-scores of the H means per step.

    Steps whose pooled mean A/A0 lies in ``[low, 1)``; ``z`` is the largest ``|m_i - m_j| / sqrt(s_i^2
    + s_j^2)`` over H pairs at each, ``rel`` the largest relative difference of ``1 - A/A0``.
    """
    mean, sem = seed_mean(1.0 - ds["area_fraction"])
    pooled = 1.0 - ds["area_fraction"].mean(("H", "seed"))
    steps = np.flatnonzero((1.0 - pooled.values >= low) & (pooled.values > 0))
    zs, rels = [], []
    for k in steps:
        m, s = mean.isel(step=k).values, sem.isel(step=k).values
        dm = np.abs(m[:, None] - m[None, :])
        with np.errstate(divide="ignore", invalid="ignore"):
            z = dm / np.sqrt(s[:, None] ** 2 + s[None, :] ** 2)
        zs.append(float(np.nanmax(z)))
        rels.append(float(dm.max() / m.mean()))
    return {"steps": steps, "z": np.array(zs), "rel": np.array(rels)}


def approach_tails(curve: dict) -> dict:
    """Measured ``1 - A/A0`` against Persson's ``erfc(sqrt 2 pbar)`` near full contact (A/A0 in [0.9, 1))."""
    gap = 1.0 - curve["area"]
    sel = (curve["area"] >= 0.9) & (gap > 0)
    persson = erfc(np.sqrt(2.0) * curve["pbar"])
    return {"pbar": curve["pbar"][sel], "measured": gap[sel], "persson": persson[sel],
            "ratio": gap[sel] / persson[sel]}


# ----------------------------------------------------------------------------- what users measure
def spectrum_of(ds: xr.Dataset, hurst: float) -> tuple[np.ndarray, np.ndarray]:
    """Persson's input for the scene's surfaces of Hurst exponent ``hurst``: ``(q, c)`` of the grid."""
    params = scene_surface(ds)
    return mode_spectrum(params["N"], float(ds["k_l"]), float(ds["k_s"]), hurst,
                         rms_slope=params["rms_slope"], length=params["L"])


def scene_surface(ds: xr.Dataset) -> dict:
    """``N``, ``L`` and ``rms_slope`` of the generated surfaces (the aggregate's attributes)."""
    n = int(ds.attrs["n"])
    return {"N": n, "L": float(ds.attrs["length"]), "rms_slope": float(ds["rms_slope"].mean())}


def measured_spectrum(ds: xr.Dataset, hurst: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """One surface's own ``(q, c)``: regenerated from its seed, ``c = abs(FFT / N^2)^2`` of its nonzero modes.

    :func:`~roughcontact.surfaces.synthetic.generate_surface` is deterministic in its arguments, so
    the surface the scene solved is rebuilt from the aggregate's ``N``, ``L``, cutoffs, H, seed and
    rms slope (a few hundredths of a second at N = 1024: the noise is drawn on the band's grid).
    """
    params = scene_surface(ds)
    n, length = params["N"], params["L"]
    h = generate_surface(n, float(ds["k_l"]), float(ds["k_s"]), float(hurst), int(seed),
                         rms_slope=float(ds["rms_slope"].sel(H=hurst, seed=seed)), length=length)
    power = np.abs(np.fft.fft2(h) / n**2) ** 2
    k = np.fft.fftfreq(n, 1.0 / n)
    q = 2 * np.pi / length * np.hypot(k[:, None], k[None, :])
    keep = (power > 1e-12 * power.max()) & (q > 0)
    order = np.argsort(q[keep], kind="stable")
    return q[keep][order], power[keep][order]


def gap_and_stiffness(ds: xr.Dataset, hurst: float, gammas=GAMMAS, spectra=SPECTRA, rules=W_SENSITIVITY) -> dict:
    """Seed means of the mean gap and stiffness at one H, and Persson's at the same loads.

    Persson's ``gap_persson`` and ``stiffness_persson`` use :data:`GAMMA`, the expected spectrum and
    ``w(q)`` at the middle of each shell's power (the main line); ``persson[(spectrum, gamma)]`` holds
    ``(gap, stiffness)`` for every spectrum of :data:`SPECTRA` and gamma of ``gammas``: ``expected`` at
    the seed-mean loads, ``measured`` each surface's at its own loads, then averaged over seeds;
    ``persson["rule", r]`` the same at :data:`GAMMA` with the expected spectrum for each discretisation
    ``r`` of ``rules`` (:data:`W_SENSITIVITY`). ``gap_sem`` is the seed standard error of the gap.
    """
    sub = ds.sel(H=hurst)
    e_star = float(ds.attrs["e_star"])
    q, c = spectrum_of(ds, hurst)
    p0 = sub["pressure"].mean("seed").values
    gap, gap_sem = seed_mean(sub["mean_gap"])
    k, k_sem = seed_mean(sub["contact_stiffness"])
    persson = {}
    if "expected" in spectra:
        for g in gammas:
            persson["expected", g] = (persson_mean_gap(p0, q, c, e_star=e_star, gamma=g),
                                      persson_stiffness(p0, q, c, e_star=e_star, gamma=g))
    if "measured" in spectra:
        own = {s: measured_spectrum(ds, hurst, s) for s in sub["seed"].values}
        for g in gammas:
            per_seed = [(persson_mean_gap(sub["pressure"].sel(seed=s).values, *own[s], e_star=e_star, gamma=g),
                         persson_stiffness(sub["pressure"].sel(seed=s).values, *own[s], e_star=e_star, gamma=g))
                        for s in sub["seed"].values]
            persson["measured", g] = tuple(np.mean([v[i] for v in per_seed], axis=0) for i in (0, 1))
    for rule in rules:
        if rule == "continuum":
            params = scene_surface(ds)
            a, w = power_law_terms(float(ds["k_l"]), float(ds["k_s"]), hurst, rms_slope=params["rms_slope"],
                                   length=params["L"])
            persson["rule", rule] = (persson_mean_gap_terms(p0, a, w, e_star=e_star, gamma=GAMMA),
                                     persson_stiffness_terms(p0, a, w, e_star=e_star, gamma=GAMMA))
        else:
            persson["rule", rule] = (persson_mean_gap(p0, q, c, e_star=e_star, gamma=GAMMA, rule=rule),
                                     persson_stiffness(p0, q, c, e_star=e_star, gamma=GAMMA, rule=rule))
    return {"pbar": reduced_load(sub).mean("seed").values, "area": sub["area_fraction"].mean("seed").values,
            "gap": gap.values, "gap_sem": gap_sem.values, "h_rms": float(np.sqrt(c.sum())),
            "gap_persson": persson_mean_gap(p0, q, c, e_star=e_star, gamma=GAMMA),
            "stiffness": k.values, "stiffness_sem": k_sem.values,
            "stiffness_persson": persson_stiffness(p0, q, c, e_star=e_star, gamma=GAMMA), "persson": persson}


def persson_ratio_band(curve: dict, key: str, spectrum: str, area: float, gammas=GAMMAS) -> tuple[float, ...]:
    """Measured over Persson's ``key`` (``gap`` or ``stiffness``) at ``area``, one ratio per gamma of ``gammas``."""
    return tuple(persson_ratio(curve, key, (spectrum, g), area) for g in gammas)


def persson_ratio(curve: dict, key: str, which: tuple, area: float) -> float:
    """Measured over Persson's ``key`` at ``area`` for one of ``curve["persson"]``'s entries ``which``."""
    ratio = curve[key] / curve["persson"][which][{"gap": 0, "stiffness": 1}[key]]
    return at_areas(curve["area"], ratio, curve["pbar"], (area,))[area][1]


def relative_sem(curve: dict, key: str, area: float) -> float:
    """The seed standard error of the measured ``key`` over its mean at ``area`` (interpolated as the ratios)."""
    with np.errstate(divide="ignore", invalid="ignore"):  # no gap at full contact
        rel = curve[f"{key}_sem"] / curve[key]
    return at_areas(curve["area"], rel, curve["pbar"], (area,))[area][1]


def stiffness_exponent(curve: dict, window=(0.01, 0.1)) -> tuple[float, float]:
    """Slopes ``d ln K / d ln p0`` over the steps with A/A0 in ``window``: measured and Persson's."""
    sel = (curve["area"] >= window[0]) & (curve["area"] <= window[1]) & np.isfinite(curve["stiffness"])
    x = np.log(curve["pbar"][sel])
    return (float(np.polyfit(x, np.log(curve["stiffness"][sel]), 1)[0]),
            float(np.polyfit(x, np.log(curve["stiffness_persson"][sel]), 1)[0]))


def pressure_distributions(ds: xr.Dataset, areas=AREAS) -> list[dict]:
    """Pooled ``P(p)`` at the steps nearest each of ``areas`` with Persson's, and their L1 distance.

    The distance is ``sum |P - P_Persson| dp / sum P dp`` over the bins (0: identical).
    """
    pooled = ds["pressure_distribution"].mean(("H", "seed"))
    pbar = reduced_load(ds).mean(("H", "seed")).values
    area = ds["area_fraction"].mean(("H", "seed")).values
    x = ds["pressure_bin"].values
    width = ds["pressure_bin_high"].values - ds["pressure_bin_low"].values
    out = []
    for a in areas:
        k = int(np.argmin(np.abs(np.log(area / a))))
        measured = pooled.isel(step=k).values
        theory = persson_pressure_distribution(x, float(pbar[k]), rms_slope=1.0, e_star=1.0)
        distance = float(np.sum(np.abs(measured - theory) * width) / np.sum(measured * width))
        out.append({"target": a, "step": k, "area": float(area[k]), "pbar": float(pbar[k]), "x": x,
                    "measured": measured, "persson": theory, "distance": distance})
    return out


# ----------------------------------------------------------------------------- percolation
#: Dapp et al. (2012), PRL 108, 244301: the contact area percolates at A/A0 = 0.42.
DAPP_THRESHOLD = 0.42

#: Wrapping bits read as "percolates": a 4-connected cluster wraps the cell in x or in y.
WRAPS_ANY = WRAPS_X | WRAPS_Y


def percolation_brackets(ds: xr.Dataset, share: float = 0.5, connectivity: int = 4, bit: int = WRAPS_ANY) -> dict:
    """Per surface, the A/A0 bracket ``(below, at]`` of the load steps between which the contact percolates.

    With ``cluster_wrapping`` in ``ds`` (:mod:`roughcontact.statistics.wrapping`): the first step
    whose ``connectivity``-connected contact set wraps (``bit``), and the step before it. Without
    (``method = "share"``, a proxy): the last upward crossing of ``share`` by the largest cluster's
    share of the contact area. Returns ``below``, ``at`` (arrays over the surfaces), ``method``.
    """
    area = ds["area_fraction"]
    wrap = "cluster_wrapping" in ds
    below, at = [], []
    for h in ds["H"].values:
        for s in ds["seed"].values:
            a = area.sel(H=h, seed=s).values
            if wrap:
                codes = ds["cluster_wrapping"].sel(H=h, seed=s, connectivity=connectivity).values
                lo, hi = first_wrapping(codes, a, bit)
            else:
                f = (ds["cluster_max_area"] / area).sel(H=h, seed=s).values
                under = np.flatnonzero(f < share)  # at small loads one spot may hold half: take the last crossing
                k = int(under[-1]) + 1 if under.size else 0
                lo, hi = (float(a[k - 1]), float(a[k])) if 0 < k < a.size else (np.nan, np.nan)
            below.append(lo)
            at.append(hi)
    return {"below": np.array(below), "at": np.array(at), "method": "wrapping" if wrap else "share"}


def percolation_threshold(brackets: dict) -> dict:
    """The threshold from the per-surface brackets: mean of the midpoints ± ``u``.

    ``sem``: standard error of the midpoints over surfaces (the seed spread); ``half_step``: half the
    widest bracket (the step spacing, which bounds each surface's threshold); ``u``: the larger of
    the two. ``n``: surfaces with a bracket.
    """
    lo, hi = brackets["below"], brackets["at"]
    ok = np.isfinite(lo) & np.isfinite(hi)
    mid = 0.5 * (lo[ok] + hi[ok])
    sem = float(mid.std(ddof=1) / np.sqrt(mid.size)) if mid.size > 1 else float("nan")
    half = float(0.5 * np.max(hi[ok] - lo[ok])) if mid.size else float("nan")
    return {"threshold": float(mid.mean()) if mid.size else float("nan"), "sem": sem, "half_step": half,
            "u": float(np.nanmax([sem, half])), "n": int(mid.size),
            "below": (float(lo[ok].min()), float(lo[ok].max())), "at": (float(hi[ok].min()), float(hi[ok].max())),
            "below_mean": float(lo[ok].mean()), "at_mean": float(hi[ok].mean()), "method": brackets["method"]}


#: The definitions of "the contact percolates" the wrapping data hold: label and wrapping bits
#: (:mod:`roughcontact.statistics.wrapping`): a cluster wraps the cell in x or in y, in x, in y, or one
#: cluster in both directions (two independent winding vectors).
WRAPPING_DEFINITIONS = {"either": ("x or y", WRAPS_ANY), "x": ("in x", WRAPS_X), "y": ("in y", WRAPS_Y),
                        "both": ("both directions", WRAPS_BOTH)}


def percolation_definitions(ds: xr.Dataset, connectivity: int = 4) -> dict:
    """The threshold by each definition of :data:`WRAPPING_DEFINITIONS`, and the one-direction threshold ± u.

    Dapp et al. (2012) place the threshold where the leakage across the cell stops: the contact then
    blocks the flow in one direction, i.e. a cluster wraps the cell in the other. The compared
    threshold is therefore the one-direction one, the mean of the ``x`` and ``y`` thresholds (the
    surfaces are isotropic: two estimates of one number). ``u`` is the largest of half the range of
    the four definitions' thresholds (``half_range``: how much the definition alone moves it), the
    larger standard error over surfaces of the two and half the widest bracket. ``definitions`` holds
    :func:`percolation_threshold` of each; ``dual``: the one-direction threshold of 8-connected
    clusters (the contact's dual of a 4-connected gap).
    """
    if "cluster_wrapping" not in ds:
        raise ValueError("percolation_definitions needs cluster_wrapping (the percolation scenes)")
    defs = {k: percolation_threshold(percolation_brackets(ds, connectivity=connectivity, bit=bit))
            for k, (_, bit) in WRAPPING_DEFINITIONS.items()}
    dual = [percolation_threshold(percolation_brackets(ds, connectivity=8, bit=WRAPPING_DEFINITIONS[k][1]))
            for k in ("x", "y")]
    one = (defs["x"], defs["y"])
    values = [d["threshold"] for d in defs.values()]
    sem = max(d["sem"] for d in one)
    half = max(d["half_step"] for d in one)
    half_range = 0.5 * (max(values) - min(values))
    return {"threshold": 0.5 * (one[0]["threshold"] + one[1]["threshold"]), "sem": sem, "half_step": half,
            "half_range": half_range, "u": max(sem, half, half_range), "n": min(d["n"] for d in one),
            "definitions": defs, "dual": 0.5 * (dual[0]["threshold"] + dual[1]["threshold"]), "method": "wrapping"}


def cluster_counts(ds: xr.Dataset) -> dict:
    """Pooled cluster count and largest-cluster share per step, and the A/A0 of the count's maximum."""
    count = ds["cluster_count"].mean(("H", "seed")).values
    pooled_area = ds["area_fraction"].mean(("H", "seed")).values
    return {"count": count, "area": pooled_area,
            "share": (ds["cluster_max_area"] / ds["area_fraction"]).mean(("H", "seed")).values,
            "count_peak_area": float(pooled_area[int(np.argmax(count))])}

"""What accuracy costs: settings of an accuracy study, error metrics against a reference.

An accuracy study varies one numerical setting at a time — grid size N, solver
tolerance, number of load steps — around a *reference*, the most accurate setting
(finest N, tightest tol), on the same surfaces: :func:`roughcontact.generate_surface`
draws the noise on the smallest grid holding the band, so every N samples the same
continuous surface and the N axis measures discretisation error alone. The number of
seeds is a fourth, statistical axis: the mean over the first k seeds against the mean
over all seeds, at the shipped default settings.

Metrics per setting (relative errors against the reference, on the same cases):

- ``area``: A/A0 at the final load p_max (the same p0 in every load schedule);
- ``area_corrected``: the same for the perimeter-corrected area (below);
- ``kappa``: kappa = E* h' A / (A0 p0) interpolated at A/A0 = ``kappa_at`` (0.05);
- ``kappa_corrected``: the same from the perimeter-corrected area;
- ``cel_kappa``, ``cel_mu``, ``cel_beta``: the CEL constants (paper route, pooled over H).

Pixel-counted area is biased high, to first order in the grid spacing: every boundary
pixel counts whole. Yastrebov, Anciaux & Molinari (Tribol. Int. 114, 161, 2017) correct
it with the contact perimeter P: A ~ A_pix - c P dx. Here P is the length of the pixel
edges between contact and non-contact nodes (the solver's ``contact_perimeter``, per
unit area) and ``c`` defaults to :data:`PERIMETER_C`; the study also fits the ``c`` that
best removes the N dependence (:func:`fit_perimeter_c`), so the constant is measured
here, not only quoted.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

from ..core.quantities import cf_unit
from ..theory.perimeter import PERIMETER_C, perimeter_corrected_area

METRICS = ("area", "area_corrected", "kappa", "kappa_corrected", "cel_kappa", "cel_mu", "cel_beta")


AXES = ("N", "tol", "n_steps", "seeds")


def variant_label(n: str, tol: str, n_steps: str) -> str:
    """Folder name of a setting, from the config's strings: ``N{n}_tol{tol}_steps{n_steps}``."""
    return f"N{n}_tol{tol}_steps{n_steps}"


def variants(block: Mapping) -> list[dict]:
    """Settings of an accuracy block: the reference, each axis value, and the defaults.

    Returns dicts with ``label``, ``axis`` ("reference", "N", "tol", "n_steps" or
    "defaults"), ``value`` (the varied string), ``N``, ``tol``, ``n_steps`` (strings) and
    ``seeds`` (int). Settings that coincide share one label (listed once, first axis wins).
    """
    ref = block["reference"]
    out, seen = [], set()

    def add(axis, value, setting, seeds):
        label = variant_label(setting["N"], setting["tol"], setting["n_steps"])
        if label in seen:
            return
        seen.add(label)
        out.append({"label": label, "axis": axis, "value": value, "seeds": seeds, **setting})

    add("reference", "", dict(ref), block["seeds"])
    for axis in ("N", "tol", "n_steps"):
        for value in block["axes"].get(axis, []):
            add(axis, value, {**ref, axis: value}, block["seeds"])
    add("defaults", "", dict(block["defaults"]), max(int(s) for s in block["seed_axis"]))
    return out


def case_metrics(agg: xr.Dataset, *, kappa_at: float, dx: float, c: float = PERIMETER_C) -> xr.Dataset:
    """Per-case metrics of a combined contact dataset (dims k_l, k_s, H, seed, step).

    Returns variables ``area``, ``area_corrected``, ``kappa``, ``kappa_corrected`` over
    (k_l, k_s, H, seed). kappa at ``kappa_at`` is linearly interpolated in A/A0 along the
    load steps (A/A0 grows monotonically with load); a case whose curve does not reach
    ``kappa_at`` raises, naming it.
    """
    e_star = float(agg.attrs.get("e_star", 1.0))
    area = agg["area_fraction"]
    corr = xr.apply_ufunc(perimeter_corrected_area, area, agg["contact_perimeter"], kwargs={"dx": dx, "c": c})
    p0 = agg["pressure"]
    hp = agg["rms_slope"]
    kap = e_star * hp * area / p0
    kap_c = e_star * hp * corr / p0

    def at(a, k):
        if not (a.min() <= kappa_at <= a.max()):
            raise ValueError(f"A/A0 range [{a.min():.4g}, {a.max():.4g}] does not reach kappa_at={kappa_at}")
        return np.interp(kappa_at, a, k)

    def interp(a, k):
        return xr.apply_ufunc(at, a, k, input_core_dims=[["step"], ["step"]], vectorize=True)

    return xr.Dataset({
        "area": area.isel(step=-1, drop=True),
        "area_corrected": corr.isel(step=-1, drop=True),
        "kappa": interp(area, kap),
        "kappa_corrected": interp(corr, kap_c),
    })


def relative_error(value, reference):
    """|value - reference| / |reference| [1] (NaN-safe: NaN where either is NaN)."""
    value, reference = np.asarray(value, float), np.asarray(reference, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.abs(value - reference) / np.abs(reference)


def fit_perimeter_c(areas: Sequence[float], perimeters: Sequence[float], dxs: Sequence[float],
                    reference: float) -> float:
    """The c minimising sum_N (A_pix - c P dx - A_ref)^2 over a resolution series [1].

    ``areas`` (A_pix/A0), ``perimeters`` (per unit area) and ``dxs`` are per grid size;
    ``reference`` is the converged area fraction. Closed-form linear least squares.
    """
    a, p, d = (np.asarray(v, float) for v in (areas, perimeters, dxs))
    x = p * d
    if not np.any(x > 0):
        raise ValueError("no contact perimeter in the series: c is undetermined")
    return float(np.sum(x * (a - reference)) / np.sum(x * x))


def solver_work(agg: xr.Dataset, n: int) -> float:
    """Mean solver work of a setting's cases: ``N² x`` its iterations summed over the load steps [1].

    A machine-independent cost (an iteration is about one FFT pair over the N² nodes), counted so
    that the study's outputs are the same bytes on every rerun; a job's wall time and memory are
    Snakemake's benchmark (``python -m roughcontact.pipeline.runcost``).

    Examples
    --------
    >>> its = xr.DataArray([[10, 20], [30, 40]], dims=("seed", "step"))
    >>> solver_work(xr.Dataset({"iterations": its}), 4)
    800.0
    """
    per_case = agg["iterations"].sum("step")
    return float(per_case.mean()) * n * n


def cost_table(summary: xr.Dataset, metric: str, targets: Sequence[float] = (1e-2, 1e-3)) -> dict:
    """Cheapest setting reaching each relative-error target for ``metric``.

    Returns {target: (label, work per case [node-iterations]) or None if no setting reaches it}.
    """
    err = summary[f"err_{metric}"].values
    work = summary["work_per_case"].values
    labels = summary["variant"].values
    out = {}
    for target in targets:
        ok = np.flatnonzero(np.isfinite(err) & (err <= target))
        if ok.size == 0:
            out[target] = None
        else:
            best = ok[np.argmin(work[ok])]
            out[target] = (str(labels[best]), float(work[best]))
    return out


def _cel_constants(agg: xr.Dataset, n_boot: int) -> dict:
    """Pooled-over-H CEL constants by the paper's route, NaN where the fit fails."""
    from ..analysis.fit.grid import fit_cel

    try:
        res = fit_cel(agg, n_boot=n_boot, methods=("paper",), on_insufficient="nan")
    except ValueError:
        return {c: float("nan") for c in ("kappa", "mu", "beta")}
    sel = res["value"].sel(H_group="pooled", estimator="paper").isel(k_l=0, k_s=0)
    return {c: float(sel.sel(constant=c)) for c in ("kappa", "mu", "beta")}


def _metric_means(agg: xr.Dataset, *, kappa_at: float, dx: float, n_boot: int, c: float) -> dict:
    m = case_metrics(agg, kappa_at=kappa_at, dx=dx, c=c)
    out = {name: float(m[name].mean()) for name in m.data_vars}
    out.update({f"cel_{k}": v for k, v in _cel_constants(agg, n_boot).items()})
    out["perimeter"] = float(agg["contact_perimeter"].isel(step=-1).mean())
    return out


def summarize(results: Mapping[str, xr.Dataset],
              settings: Sequence[Mapping], *, length: float, kappa_at: float = 0.05,
              seed_axis: Sequence[str] = (), n_boot: int = 10, c: float = PERIMETER_C,
              length_unit: str = "1") -> xr.Dataset:
    """Errors and costs of every setting of an accuracy study.

    Parameters
    ----------
    results : mapping label -> combined contact dataset of the setting (with ``iterations`` per step)
    settings : the output of :func:`variants`
    length : domain side L (grid spacing L/N)
    seed_axis : numbers of seeds (strings) compared at the "defaults" setting
    length_unit : unit of ``length`` (:data:`roughcontact.core.quantities.LENGTH_UNITS`, default
        ``"1"``), recorded as the attribute ``length_units``; the metrics are dimensionless

    Returns
    -------
    xarray.Dataset over dim ``variant`` (one row per N/tol/n_steps setting, plus one per
    entry of ``seed_axis``) with coords ``axis``, ``value``, ``N``, ``tol``, ``n_steps``,
    ``n_seeds`` and variables ``work_per_case`` [1] (:func:`solver_work`), the metric values
    and ``err_<metric>`` (relative error against the reference; for the seeds axis against
    the all-seeds mean at the defaults). Attr ``perimeter_c_fit``: the c that best
    removes the N dependence of A/A0 at p_max (:func:`fit_perimeter_c`).
    """
    ref = next(s for s in settings if s["axis"] == "reference")
    d = next(s for s in settings if s["axis"] == "defaults")
    metric_kw = dict(kappa_at=kappa_at, n_boot=n_boot, c=c)
    rows = _setting_rows(results, settings, results[ref["label"]], length, metric_kw)
    ref_vals = next(r["vals"] for r in rows if r["axis"] == "reference")
    for r in rows:
        r["err"] = {k: float(relative_error(r["vals"][k], ref_vals[k])) for k in METRICS}
    rows += _seed_rows(results[d["label"]], d, seed_axis, length, metric_kw)

    n_axis = [r for r in rows if r["axis"] in ("N", "reference")]
    if len(n_axis) > 1:
        c_fit = fit_perimeter_c([r["vals"]["area"] for r in n_axis], [r["vals"]["perimeter"] for r in n_axis],
                                [length / int(r["N"]) for r in n_axis], ref_vals["area"])
    else:
        c_fit = float("nan")
    return _summary_dataset(rows, attrs={
        "reference": ref["label"], "defaults": d["label"], "kappa_at": float(kappa_at),
        "perimeter_c": float(c), "perimeter_c_fit": c_fit, "length": float(length),
        "length_units": cf_unit(length_unit, length_power=1)})


def _setting_rows(results, settings, ref_agg: xr.Dataset, length: float, metric_kw: dict) -> list[dict]:
    """One row per setting: its metrics on the reference's (H, seed) cases and its solver work."""
    rows = []
    for s in settings:
        agg = results[s["label"]]
        dx = length / int(s["N"])
        try:
            vals = _metric_means(agg.sel(H=ref_agg["H"], seed=ref_agg["seed"]), dx=dx, **metric_kw)
        except ValueError as exc:
            raise ValueError(f"setting {s['label']}: {exc}; lower p_max/n_steps or change kappa_at") from None
        rows.append(dict(label=s["label"], axis=s["axis"], value=s["value"], N=s["N"], tol=s["tol"],
                         n_steps=s["n_steps"], n_seeds=int(ref_agg.sizes["seed"]),
                         work=solver_work(agg, int(s["N"])), vals=vals))
    return rows


def _seed_rows(result, d: Mapping, seed_axis: Sequence[str], length: float, metric_kw: dict) -> list[dict]:
    """One row per entry of ``seed_axis``: the first k seeds at the defaults against all of them."""
    agg_d = result
    dx_d = length / int(d["N"])
    all_vals = _metric_means(agg_d, dx=dx_d, **metric_kw)
    rows = []
    for k_text in seed_axis:
        k = int(k_text)
        vals = _metric_means(agg_d.isel(seed=slice(0, k)), dx=dx_d, **metric_kw)
        rows.append(dict(label=f"{d['label']}_seeds{k_text}", axis="seeds", value=k_text, N=d["N"], tol=d["tol"],
                         n_steps=d["n_steps"], n_seeds=k,
                         work=solver_work(agg_d, int(d["N"])) * k * agg_d.sizes["H"], vals=vals,
                         err={m: float(relative_error(vals[m], all_vals[m])) for m in METRICS}))
    return rows


def _summary_dataset(rows: list[dict], attrs: dict) -> xr.Dataset:
    """The rows as a Dataset over ``variant`` (:func:`summarize`'s Returns)."""
    one = {"units": "1"}
    data = {
        "work_per_case": ("variant", [r["work"] for r in rows],
                          {"units": "1", "long_name": "solver work per case, N^2 x iterations summed over the load "
                           "steps (seeds axis: for all its cases)"}),
    }
    for m in METRICS:
        data[m] = ("variant", [r["vals"][m] for r in rows],
                   {**one, "long_name": f"{m} (mean over cases)", "allow_nan": 1})
        data[f"err_{m}"] = ("variant", [r["err"][m] for r in rows],
                            {**one, "long_name": f"relative error of {m} against the reference", "allow_nan": 1})
    coords = {
        "variant": ("variant", [r["label"] for r in rows], {**one, "long_name": "setting label"}),
        "axis": ("variant", [r["axis"] for r in rows], {**one, "long_name": "axis varied (reference: none)"}),
        "value": ("variant", [r["value"] for r in rows], {**one, "long_name": "value of the varied setting"}),
        "N": ("variant", [int(r["N"]) for r in rows], {**one, "long_name": "grid points per side"}),
        "tol": ("variant", [float(r["tol"]) for r in rows], {**one, "long_name": "solver tolerance"}),
        "n_steps": ("variant", [int(r["n_steps"]) for r in rows], {**one, "long_name": "load steps"}),
        "n_seeds": ("variant", [r["n_seeds"] for r in rows], {**one, "long_name": "seeds per H"}),
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def markdown_table(summary: xr.Dataset) -> str:
    """The summary as a markdown table (solver work, relative errors in %)."""
    cols = ["area", "area_corrected", "kappa", "kappa_corrected", "cel_kappa", "cel_mu", "cel_beta"]
    head = "| axis | setting | work per case [10⁹ N² × iterations] | " + \
        " | ".join(f"err {c} [%]" for c in cols) + " |"
    lines = [head, "|" + "---|" * (3 + len(cols))]
    for i in range(summary.sizes["variant"]):
        row = summary.isel(variant=i)
        errs = " | ".join(f"{100 * float(row[f'err_{c}']):.3g}" for c in cols)
        lines.append(f"| {row['axis'].item()} | {row['variant'].item()} | {float(row['work_per_case']) / 1e9:.3g} | "
                     f"{errs} |")
    return "\n".join(lines) + "\n"

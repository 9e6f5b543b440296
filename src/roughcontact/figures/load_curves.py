"""What the load-curve figures share (Yastrebov, Anciaux & Molinari 2012, Figs. 2-4; the measured scene's too).

Each ``fig_*`` function takes datasets and returns a :class:`matplotlib.figure.Figure`
built without pyplot (no global figure registry, no GUI backend); :func:`save_figure`
writes it as PNG and PDF with byte-identical output on every rerun.

Conventions: every figure is 7 in wide (:data:`~.style.FIGURE_WIDTH_IN`), one panel sized for a column; legends sit
outside the axes; colours are the Okabe-Ito palette (distinguishable with the common
colour-vision deficiencies), one colour per Hurst exponent; the long cutoff
``lambda_l = L / k_l`` is told apart by marker and line style. Theory curves are black
or grey, except Persson's, in reddish purple (:data:`PERSSON_COLOUR`). Load steps whose solve
did not converge are left out of every line and seed mean, drawn as grey crosses
(:data:`UNCONVERGED_STYLE`) and counted in the legend. Symbols: ``p0``
applied mean pressure, ``E*`` contact modulus, ``h'`` rms slope, ``A/A0`` contact-area
fraction, ``pbar`` mean contact pressure, ``kappa = E* h' / pbar``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.lines import Line2D

from ..analysis.aggregate import is_profiles
from ..analysis.aggregate.seeds import seed_reduce
from ..analysis.fit.estimators import at_bound
from ..theory.laws import KAPPA_BGT
from ..theory.summits import NAYAK_ALPHA_MIN
from .captions import PROFILES_GID, REFERENCE_STYLES, ROUTE_LEGEND
from .record import note, note_fit, note_left_out, note_series
from .style import OKABE_ITO, STYLE, at_interval, family_styles, lambda_label, new_figure, panel_grid, pick, require

#: Persson's (2001) two curves: one colour, told apart by style (they coincide at small load).
PERSSON_COLOUR = OKABE_ITO[6]
PERSSON_LIMIT_STYLE = {"color": PERSSON_COLOUR, "lw": 1.0, "ls": (0, (4, 2))}
PERSSON_ERF_STYLE = {"color": PERSSON_COLOUR, "lw": 2.6, "ls": "-", "alpha": 0.45}


def run_summary(agg: xr.Dataset, stats: xr.Dataset) -> str:
    """What a contact figure shows, for its title: grid N, seeds per curve times the values of H (what an
    H-pooled fit pools: 3 seeds x 2 values of H are 6 surfaces per (k_l, k_s)), load range."""
    parts = []
    try:
        recorded = json.loads(agg.attrs.get("scene_parameters", "{}"))
    except ValueError:
        recorded = {}
    n = recorded.get("surface", {}).get("N") if isinstance(recorded, dict) else None
    if n is not None:
        parts.append(f"$N = {int(n)}$")
    seeds = stats["n_seeds"].values[stats["n_seeds"].values > 0] if "n_seeds" in stats else np.array([])
    if seeds.size:
        lo, hi = int(seeds.min()), int(seeds.max())
        n_h = int((stats["n_seeds"] > 0).any([d for d in stats["n_seeds"].dims if d != "H"]).sum()) \
            if "H" in stats["n_seeds"].dims else 1
        text = f"{lo} seeds" if lo == hi else f"{lo}-{hi} seeds"
        parts.append(text + (rf" $\times$ {n_h} values of $H$" if n_h > 1 else ""))
    if "pressure" in agg and "e_star" in agg.attrs:
        p = agg["pressure"].values / float(agg.attrs["e_star"])
        if np.isfinite(p).any():
            parts.append(f"$p_0/E^*$ = {np.nanmin(p):.3g}-{np.nanmax(p):.3g}")
    return ", ".join(parts)


def fit_constants(fit: xr.Dataset | None, k_l: float, k_s: float, estimator: str):
    """(kappa, mu, beta) of the H-pooled fit, or None where absent/NaN."""
    if fit is None:
        return None
    require(fit, "fit", ("value",))
    if estimator not in list(fit["estimator"].values):
        raise ValueError(f"estimator={estimator!r} is not in fit (has {list(fit['estimator'].values)})")
    try:
        v = fit["value"].sel({"k_l": k_l, "k_s": k_s, "H_group": "pooled", "estimator": estimator})
    except KeyError:
        return None
    vals = [float(v.sel(constant=c)) for c in ("kappa", "mu", "beta")]
    return tuple(vals) if np.all(np.isfinite(vals)) else None


def has_seeds(stats: xr.Dataset, k_l: float, k_s: float, h: float) -> bool:
    """Whether the ``(k_l, k_s, H)`` family has at least one seed in ``stats`` (the aggregate's seed statistics)."""
    return int(stats["n_seeds"].sel(k_l=k_l, k_s=k_s, H=h)) > 0


def title_figure(fig, agg: xr.Dataset, stats: xr.Dataset, left_out: Sequence[str] = ()) -> None:
    """The figure's title (:func:`run_summary`); a figure of profiles says so in it, is tagged
    :data:`~.captions.PROFILES_GID` and notes it (:func:`mark_profiles`, with what it ``left_out`` for them), so
    that its caption says which references are 2-D laws."""
    if is_profiles(agg):
        mark_profiles(fig, left_out)
        fig.suptitle("profiles (1-D, plane strain), " + run_summary(agg, stats))
        return
    fig.suptitle(run_summary(agg, stats))


#: What a figure that draws the asperity models leaves out for profiles (:func:`asperity_alphas` gives none).
NO_ASPERITY = ("asperity",)


def mark_profiles(fig, left_out: Sequence[str] = ()) -> None:
    """Tag a contact figure of profiles (:data:`~.captions.PROFILES_GID`) and note what its caption says of them:
    what ``A/A0`` and ``h'`` mean for a profile, and what the figure leaves out for them (``left_out``: keys of
    :data:`~.captions.LEFT_OUT`, e.g. :data:`NO_ASPERITY` for a figure that draws the asperity models)."""
    fig.set_gid(PROFILES_GID)
    note(fig, "profiles_contact")
    note_left_out(fig, *left_out)


def family_name(family: Mapping) -> str:
    """A ``(k_l, k_s, H)`` family's name as a record's data series: ``"k_l = 4, k_s = 32, H = 0.36"``."""
    return ", ".join(f"{k} = {float(family[k]):g}" for k in ("k_l", "k_s", "H"))


def note_families(fig, families) -> None:
    """Record the families ``(kl, ks, h)`` (or mappings) drawn on ``fig`` as its data series."""
    note_series(fig, [family_name(f if isinstance(f, Mapping) else dict(zip(("k_l", "k_s", "H"), f, strict=True)))
                      for f in families])


def note_fit_curves(fig, gid: str, route: str, label: str, where, fit: xr.Dataset) -> None:
    """Record every line tagged ``gid`` on ``fig``'s axes as a fitted curve of ``route`` with the legend ``label``,
    fitted to the group ``where(ax)`` (plain text, from the line's axes) over the window of ``fit``."""
    window = (float(fit.attrs.get("window_low", np.nan)), float(fit.attrs.get("window_high", np.nan)))
    for ax in fig.axes:
        for line in ax.get_lines():
            if line.get_gid() == gid:
                note_fit(fig, line, route, label, where(ax), window)


def e_star_of(agg: xr.Dataset) -> float:
    """The modulus ``E*`` [pressure] of an aggregate (its ``e_star`` attribute), checked finite and > 0."""
    if "e_star" not in agg.attrs:
        raise ValueError("agg lacks the global attribute 'e_star'")
    e = float(agg.attrs["e_star"])
    if not (np.isfinite(e) and e > 0):
        raise ValueError(f"agg.attrs['e_star'] must be finite and > 0, got {agg.attrs['e_star']!r}")
    return e


# -------------------------------------------------------------- unconverged steps
#: Load steps whose solve did not converge: small grey crosses under the data, out of the means.
UNCONVERGED_STYLE = {"color": "0.5", "marker": "x", "ls": "none", "ms": 3.0, "mew": 0.7}


def unconverged_steps(ds: xr.Dataset, present: xr.DataArray | bool | None = None) -> xr.DataArray | None:
    """The load steps that did not converge: boolean, dims of ``ds.converged`` (``(k_l, k_s, H,
    seed, step)`` or ``(topography, step)``); None where ``ds`` has no ``converged`` (files of
    older versions: every step is taken as converged).

    Only the steps of cases in ``present`` count (default ``ds.case_present``: a grid hole, whose
    ``converged`` is False, has no steps); ``True`` counts every case.
    """
    if "converged" not in ds:
        return None
    if present is None:
        present = ds["case_present"].astype(bool) if "case_present" in ds else True
    return ~ds["converged"].astype(bool) & present


def converged_family(agg: xr.Dataset, stats: xr.Dataset, bad: xr.DataArray | None, family: Mapping,
                      names: Sequence[str]) -> dict[str, np.ndarray]:
    """Seed statistics of one family over its converged steps, by name, shape ``(n_steps,)`` each.

    ``family``: ``{"k_l": .., "k_s": .., "H": ..}``; ``names``: statistics of
    :func:`roughcontact.analysis.aggregate.seed_statistics` (``"kappa_mean"``, ``"area_fraction_std"``,
    ``"pressure_mean"`` ...), in the units of their variable; ``bad``: :func:`unconverged_steps` of
    ``agg``. Taken from ``stats`` where every step of the family converged (or ``bad`` is None),
    else recomputed from ``agg`` by :func:`roughcontact.analysis.aggregate.seed_statistics`' reduction
    with the unconverged ``(seed, step)`` left out (a step none of whose seeds converged is NaN,
    and so is the s.d. of a step with one converged seed).
    """
    fam_bad = None if bad is None else bad.sel(family)
    if fam_bad is None or not bool(fam_bad.any()):
        return {name: stats[name].sel(family).values for name in names}
    case = agg.sel(family)
    ok = ~fam_bad & (case["case_present"].astype(bool) if "case_present" in case else True)
    n_ok = ok.sum("seed")
    out = {}
    for name in names:
        var, stat = name.rsplit("_", 1)
        out[name] = seed_reduce(case[var], ok, n_ok, var, "1")[stat].transpose("step").values
    return out


def masked_points(x: xr.DataArray, y: xr.DataArray, mask: xr.DataArray) -> tuple[np.ndarray, np.ndarray]:
    """``x`` and ``y`` where ``mask`` is True, broadcast against each other, flattened: shape ``(n,)`` each."""
    x, y, mask = (v.transpose(*mask.dims) for v in xr.broadcast(x, y, mask))
    m = mask.values.astype(bool)
    return x.values[m].astype(float), y.values[m].astype(float)


def family_unconverged(agg: xr.Dataset, bad: xr.DataArray | None, family: Mapping, x: str,
                        y: str) -> tuple[np.ndarray, np.ndarray]:
    """Values of the variables ``x`` and ``y`` at the unconverged steps (``bad``, :func:`unconverged_steps`)
    of one family, shape ``(n,)`` each."""
    mask = None if bad is None else bad.sel(family)
    if mask is None or not bool(mask.any()):
        return np.array([]), np.array([])
    case = agg.sel(family)
    return masked_points(case[x], case[y], mask)


def draw_unconverged(ax, x: np.ndarray, y: np.ndarray) -> None:
    """The unconverged steps ``(x, y)``, shape ``(n,)`` each, as crosses (nothing for ``n = 0``)."""
    if x.size:
        ax.plot(x, y, zorder=1.5, **UNCONVERGED_STYLE)


def n_outside(ax, x: np.ndarray, y: np.ndarray) -> int:
    """How many points ``(x, y)`` the axes do not show at their current limits (non-finite ones,
    and non-positive ones on a log axis, included)."""
    inside = np.isfinite(x) & np.isfinite(y)
    with np.errstate(invalid="ignore"):
        for v, (lo, hi), scale in ((x, ax.get_xlim(), ax.get_xscale()), (y, ax.get_ylim(), ax.get_yscale())):
            inside &= (v >= min(lo, hi)) & (v <= max(lo, hi)) & ((v > 0) if scale == "log" else True)
    return int(x.size - inside.sum())


def unconverged_handles(n: int, n_off: int, left_out_of: str = "lines and means") -> list[Line2D]:
    """Legend entry of ``n`` unconverged steps, ``n_off`` of them outside the axes; none for ``n = 0``."""
    if not n:
        return []
    off = f"; {n_off} outside the axes" if n_off else ""
    return [Line2D([], [], **UNCONVERGED_STYLE,
                   label=f"{n} unconverged load step{'s' if n != 1 else ''}, left out of the {left_out_of}{off}")]


#: Finite-load asperity models drawn in the area-load and kappa figures: line style per model.
ASPERITY_STYLES = {"bgt": (REFERENCE_STYLES["asperity_bgt"]["ls"], "BGT"),
                   "greenwood": (REFERENCE_STYLES["asperity_greenwood"]["ls"], "Greenwood (2006)")}


def asperity_gid(model: str, alpha: float) -> str:
    """The caption tag (:data:`roughcontact.figures.captions.REFERENCES`) of an asperity model's curve:
    ``asperity_{model}_paper`` at the paper's alpha = 2, ``asperity_{model}_own`` at the surfaces' own."""
    return f"asperity_{model}_{'paper' if alpha == PAPER_ALPHA else 'own'}"


def asperity_style(model: str, colour) -> dict:
    """Line style of an asperity model's curve (:data:`~roughcontact.figures.captions.REFERENCE_STYLES`)."""
    return {**REFERENCE_STYLES[f"asperity_{model}"], "color": colour}


def reference_style(name: str) -> dict:
    """Line style of a reference line (:data:`roughcontact.figures.captions.REFERENCE_STYLES`), for a legend
    handle (without its zorder)."""
    return {k: v for k, v in REFERENCE_STYLES[name].items() if k != "zorder"}


#: The paper's contact evolution law (Yastrebov et al. 2012): kappa, mu, beta.
PAPER_CONSTANTS = {"kappa": 1.145 * KAPPA_BGT, "mu": 0.55, "beta": 0.21}


PAPER_CEL_LABEL = r"CEL, paper: $\kappa/\sqrt{2\pi}$ = 1.145, $\mu$ = 0.55, $\beta$ = 0.21"


BGT_LIMIT_LABEL = r"BGT small-load limit, $\kappa=\sqrt{2\pi}$"


#: Nayak's bandwidth of the paper's Fig. 5 comparison (Carbone & Bottiglione 2008).
PAPER_ALPHA = 2.0


#: Largest relative spread of the cases' Nayak alpha for which one "these surfaces" curve is drawn.
ALPHA_SPREAD_MAX = 0.1


def asperity_alphas(agg: xr.Dataset) -> list[tuple[float, str, str]]:
    """``(alpha, colour, label)`` of the asperity curves: the paper's alpha = 2 and, when the
    surfaces carry it, it differs and the cases share it (relative spread of the means per
    (k_l, k_s) family at most :data:`ALPHA_SPREAD_MAX`), their own mean Nayak bandwidth
    (profile moments).

    Families of different bandwidth (k_s / k_l from 2 to 128 gives alpha from ~1.5 to ~30)
    have no common alpha: their mean would be a curve that describes none of them. None for profiles
    (:func:`roughcontact.analysis.aggregate.is_profiles`): the models count a 2-D surface's summits.
    """
    if is_profiles(agg):  # the asperity models are of a 2-D surface's summits: no prediction for a profile
        return []
    out = [(PAPER_ALPHA, "0.15", r"$\alpha = 2$ (paper)")]
    if "alpha" in agg:
        present = agg["case_present"] if "case_present" in agg else True
        alphas = agg["alpha"].where(present)
        family = alphas.mean([d for d in alphas.dims if d not in ("k_l", "k_s")], skipna=True)
        alpha = float(alphas.mean(skipna=True))
        spread = (float(family.max(skipna=True)) - float(family.min(skipna=True))) / alpha if family.size else 0.0
        if (np.isfinite(alpha) and alpha >= NAYAK_ALPHA_MIN and abs(alpha - PAPER_ALPHA) > 0.005
                and spread <= ALPHA_SPREAD_MAX):
            out.append((alpha, "0.6", rf"$\alpha = {alpha:.2f}$ (these surfaces)"))
    return out


def asperity_handles(alphas) -> list[Line2D]:
    """Legend handles of the asperity models' curves, one per model and Nayak alpha of ``alphas``."""
    return [Line2D([], [], **{k: v for k, v in asperity_style(model, colour).items() if k != "zorder"},
                   label=f"{name}, {label}")
            for alpha, colour, label in alphas for model, (_ls, name) in ASPERITY_STYLES.items()]


def mean_slope(stats: xr.Dataset) -> float:
    """The mean rms slope ``h'`` of a study's cases with seeds (every case shares the target slope)."""
    # All cases of a study share the target rms slope; its mean sets the theory lines.
    hp = stats["rms_slope_mean"].where(stats["n_seeds"] > 0)
    v = float(hp.mean(skipna=True))
    if not (np.isfinite(v) and v > 0):
        raise ValueError("stats has no finite positive rms_slope_mean")
    return v


def _selection(stats, k_l, k_s, hurst):
    ks_list = pick(stats["k_s"].values, k_s, "k_s")
    kl_list = pick(stats["k_l"].values, k_l, "k_l")
    h_list = pick(stats["H"].values, hurst, "hurst")
    ks_list = [ks for ks in ks_list
               if any(has_seeds(stats, kl, ks, h) for kl in kl_list for h in h_list)]
    if not ks_list:
        raise ValueError("no (k_l, k_s, H) family with data in the selection")
    return kl_list, ks_list, h_list


# ---------------------------------------------------------------------- figures
def family_panels(stats, k_l, k_s, hurst, fit_k_l):
    """Selection, styles, the k_l of the drawn CEL, and one panel per k_s (Figs. 2-4)."""
    kl_list, ks_list, h_list = _selection(stats, k_l, k_s, hurst)
    colour, marker, style = family_styles(kl_list, h_list)
    cel_kl = kl_list[-1] if fit_k_l is None else pick(stats["k_l"].values, fit_k_l, "fit_k_l")[0]
    nrows, ncols, height = panel_grid(len(ks_list))
    with matplotlib.rc_context(STYLE):
        fig = new_figure(height)
        axes = fig.subplots(nrows, ncols, squeeze=False)
    return kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes


#: The +-1 s.d. bands of the area-load figure: face and edge opacity, edge width [pt].
BAND_ALPHA, BAND_EDGE_ALPHA, BAND_EDGE_LW = 0.3, 0.8, 0.6


def constrained_constants(fit: xr.Dataset, where: Mapping, estimator: str,
                           constants: Sequence[str]) -> dict[str, bool]:
    """Per constant, whether the data constrain it: the fit's ``constrained`` flag (its rule is
    :data:`roughcontact.analysis.fit.UNCONSTRAINED_RULE`, :func:`roughcontact.analysis.fit.constrained_flags`; True
    for files without the flag) and not sitting on a bound of the fit (:func:`roughcontact.analysis.fit.at_bound`;
    the flag of fits made before that check was part of it does not say so).

    ``where``: the fit's group, e.g. ``{"k_l": 16.0, "k_s": 32.0, "H_group": "pooled"}`` (empty
    for a fit of measured topographies).
    """
    sub = fit.sel({**where, "estimator": estimator})
    out = {}
    for c in constants:
        flag = bool(sub["constrained"].sel(constant=c)) if "constrained" in sub else True
        out[c] = flag and not at_bound(estimator, c, float(sub["value"].sel(constant=c)))
    return out


def fit_constrained(fit: xr.Dataset, k_l: float, k_s: float, estimator: str,
                     constants: Sequence[str] = ("kappa", "mu", "beta")) -> bool:
    """Whether ``constants`` of the H-pooled fit are all constrained by the data (:func:`constrained_constants`)."""
    where = {"k_l": k_l, "k_s": k_s, "H_group": "pooled"}
    return all(constrained_constants(fit, where, estimator, constants).values())


#: The CEL's constants, in the order of a fit's ``constant`` coordinate; their mathtext in a legend, and the
#: factor a legend divides each by (kappa is shown as kappa/sqrt(2 pi), as the paper gives it).
CEL_CONSTANTS = ("kappa", "mu", "beta")
CONSTANT_TEX = {"kappa": r"$\kappa/\sqrt{2\pi}$", "mu": r"$\mu$", "beta": r"$\beta$"}
CONSTANT_SCALE = {"kappa": KAPPA_BGT, "mu": 1.0, "beta": 1.0}


def fit_estimates(fit: xr.Dataset, where: Mapping, estimator: str) -> dict[str, tuple[float, float, float]]:
    """``(value, ci_low, ci_high)`` [1] of each CEL constant of the fit's group ``where`` (e.g. ``{"k_l": 16.0,
    "k_s": 32.0, "H_group": "pooled"}``; empty for a fit of measured topographies) by ``estimator``; the
    interval NaN where the fit has none."""
    sub = fit.sel({**where, "estimator": estimator})
    out = {}
    for c in CEL_CONSTANTS:
        ends = [float(sub[v].sel(constant=c)) if v in sub else float("nan") for v in ("ci_low", "ci_high")]
        out[c] = (float(sub["value"].sel(constant=c)), *ends)
    return out


def constant_text(name: str, estimate: tuple[float, float, float]) -> str:
    r"""``$\mu$ = 0.54``: a constant's value for a legend, rounded to its interval (:func:`~.style.at_interval`)."""
    scale = CONSTANT_SCALE[name]
    return f"{CONSTANT_TEX[name]} = " + at_interval(*(v / scale for v in estimate))


def cel_fit_label(fit: xr.Dataset, ks_list: Sequence[float], cel_kl: float, estimator: str) -> str:
    """The legend entry of the fitted CEL curves of a figure of one panel per ``k_s`` of ``ks_list``
    (:func:`fit_label`): the constants of the one panel, or the panels where they are not constrained."""
    loose = [ks for ks in ks_list if not fit_constrained(fit, cel_kl, ks, estimator)]
    one = len(ks_list) == 1
    estimates = fit_estimates(fit, {"k_l": cel_kl, "k_s": ks_list[0], "H_group": "pooled"}, estimator) if one else None
    return fit_label(estimator, cel_kl, estimates, not loose,
                     where="" if one else ", ".join(lambda_label(ks, "s") for ks in loose))


def record_panels(fig, axes, agg: xr.Dataset, stats: xr.Dataset, lists, fit, cel_kl: float, estimator: str,
                  drew_fit: bool) -> str | None:
    """What a figure of one panel per ``k_s`` records once drawn, and its title: its families (``lists``:
    ``(kl_list, ks_list, h_list)``), the fitted CEL curves with their legend entry (:func:`cel_fit_label`,
    returned; None without a fit), and the title (:func:`title_figure`; profiles leave out the asperity models)."""
    kl_list, ks_list, h_list = lists
    note_families(fig, [(kl, ks, h) for ks in ks_list for kl in kl_list for h in h_list if has_seeds(stats, kl, ks, h)])
    label = None
    if drew_fit:
        label = cel_fit_label(fit, ks_list, cel_kl, estimator)
        note_cel_fits(fig, axes, ks_list, cel_kl, estimator, label, fit)
    title_figure(fig, agg, stats, NO_ASPERITY)
    return label


def note_cel_fits(fig, axes, ks_list: Sequence[float], cel_kl: float, estimator: str, label: str, fit,
                  gid: str = "cel_fit") -> None:
    """Record the fitted curves (lines tagged ``gid``) of the panels ``axes`` (one per ``k_s`` of ``ks_list``):
    the route ``estimator``, the legend ``label``, the group each was fitted to and the fit's window."""
    ks_of = {ax: ks for ax, ks in zip(axes, ks_list, strict=False)}
    note_fit_curves(fig, gid, estimator, label,
                    lambda ax: f"k_l = {cel_kl:g}, k_s = {ks_of.get(ax, float('nan')):g}, H pooled", fit)


def fit_label(estimator: str, k_l: float, estimates=None, constrained: bool = True, where: str = "") -> str:
    """Legend text of a fitted CEL curve: its route (:data:`~.captions.ROUTE_LEGEND`) and, when one curve is
    drawn and the data constrain them, its constants rounded to their intervals (``estimates``:
    :func:`fit_estimates`; else "not constrained": an interval wider than the value is no number; ``where``
    names the panels where they are not, when there are several)."""
    text = f"CEL fitted ({ROUTE_LEGEND[estimator]}), " + lambda_label(k_l, "l")
    if not constrained:
        return text + ": not constrained by the data" + (f" at {where}" if where else "")
    if estimates is not None:
        text += ": " + ", ".join(constant_text(c, estimates[c]) for c in CEL_CONSTANTS)
    return text

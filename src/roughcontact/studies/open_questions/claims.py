"""The open-questions answers as claim rows: question, comparison, measured, verdict, rule.

As in :mod:`roughcontact.studies.verdicts`, each verdict is its printed rule applied to the printed
``measured`` text (:data:`RULES`; ``verdicts.check_table(markdown, RULES)`` re-derives every verdict
of a published table from its text).
"""

from __future__ import annotations

import numpy as np

from ..verdicts import NUMBER, Rule, floats_matching, judged_row


def _share(fraction: float) -> str:
    return "yes" if fraction == 1 else "partly" if fraction >= 0.5 else "no"


def _cel(comparison: str, measured: str) -> str:
    [(at5,)] = floats_matching(rf"5 % crossing at A/A0 = ({NUMBER})", measured)
    [(at4,)] = floats_matching(rf"4 % crossing at A/A0 = ({NUMBER})", measured)
    return "yes" if min(at5, at4) >= 0.5 else "partly" if at5 >= 0.11 else "no"


def _persson_area(comparison: str, measured: str) -> str:
    devs = [abs(d) for _, d in floats_matching(rf"at A/A0 = ({NUMBER}): ({NUMBER}) %", measured)]
    return "yes" if all(d <= 5 for d in devs) else "partly" if all(d <= 5 for d in devs[-2:]) else "no"


def _onset(comparison: str, measured: str) -> str:
    [(k, n)] = floats_matching(rf"consistent in ({NUMBER}) of ({NUMBER}) cases", measured)
    return "yes" if k == n else "no"


def _h_independent(comparison: str, measured: str) -> str:
    [(k, n)] = floats_matching(rf"z ≤ 3 at ({NUMBER}) of ({NUMBER}) steps", measured)
    return _share(k / n) if n else "no"


def _tail(comparison: str, measured: str) -> str:
    [(lo, hi)] = floats_matching(rf"ratio from ({NUMBER}) to ({NUMBER})", measured)
    return "yes" if 0.5 <= lo and hi <= 2.0 else "no"


def _ratio_bands(comparison: str, measured: str) -> str:
    bands = floats_matching(rf"({NUMBER}) \[({NUMBER}), ({NUMBER})\] \(H=({NUMBER})\)", measured)
    rules = floats_matching(rf"({NUMBER}) / ({NUMBER}) / ({NUMBER}) \(H=", measured)
    central = [0.9 <= r <= 1.1 for r, _, _, _ in bands]
    whole = [0.9 <= lo and hi <= 1.1 for _, lo, hi, _ in bands] + [0.9 <= v <= 1.1 for r in rules for v in r]
    if all(whole) and "pending" not in measured:
        return "yes"
    return "partly" if np.mean(central) >= 0.5 else "no"


def _distance(comparison: str, measured: str) -> str:
    d = [v for _, v in floats_matching(rf"A/A0 = ({NUMBER}): ({NUMBER})", measured)]
    return _share(float(np.mean([v <= 0.1 for v in d])))


def _percolation(comparison: str, measured: str) -> str:
    [(m, u)] = floats_matching(rf"threshold A/A0 = ({NUMBER}) ± ({NUMBER})", measured)
    off = abs(m - 0.42)
    return "yes" if off <= 2 * u and u <= 0.01 else "partly" if off <= max(2 * u, 0.05) else "no"


def _bend(comparison: str, measured: str) -> str:
    whole = floats_matching(rf"all {NUMBER} points[^:]*: slope = ({NUMBER}) ± ({NUMBER}), curvature = ({NUMBER}) ± "
                            rf"({NUMBER})", measured)
    above = floats_matching(rf"α ≥ {NUMBER} \({NUMBER} points\): slope = ({NUMBER}) ± ({NUMBER}), curvature = "
                            rf"({NUMBER}) ± ({NUMBER})", measured)

    def one(fit, upper):
        (m, e, c, ce), (um, ue, uc, uce) = fit, upper
        if abs(m) > 3 * e and abs(c) <= 2 * ce:
            return "yes"
        return "partly" if abs(m) > 3 * e and abs(um) > 3 * ue and abs(uc) <= 2 * uce else "no"

    verdicts = {one(f, u) for f, u in zip(whole, above, strict=True)}
    return verdicts.pop() if len(verdicts) == 1 else "partly"  # a sensitivity flips it: partly


def _slope(comparison: str, measured: str) -> str:
    [(m, e)] = floats_matching(rf"slope = ({NUMBER}) ± ({NUMBER})", measured)
    return "yes" if abs(m) > 3 * e else "no"


def _models(comparison: str, measured: str) -> str:
    counts = floats_matching(rf"within 5 % of (?:BGT|Greenwood) at ({NUMBER}) of ({NUMBER}) points", measured)
    best = max(k / n for k, n in counts)
    return _share(best)


def _on_trend(comparison: str, measured: str) -> str:
    zs = [z for z, in floats_matching(rf"z = ({NUMBER})", measured)]
    return _share(float(np.mean([abs(z) <= 2 for z in zs])))


def _same_kappa(comparison: str, measured: str) -> str:
    [(k, n)] = floats_matching(rf"abs\(z\) ≤ 2 at ({NUMBER}) of ({NUMBER}) points", measured)
    return _share(k / n)


def _halves(comparison: str, measured: str) -> str:
    ci = floats_matching(rf"({NUMBER}) \[({NUMBER}), ({NUMBER})\]", measured)
    contains = all(lo <= 0.5 <= hi for _, lo, hi in ci)
    excludes = all(hi < 1.0 for _, _, hi in ci)
    return "yes" if contains and excludes else "partly" if contains else "no"


_SLOPE_RULE = ("weighted least-squares slope of the seed-mean κ(0.05)/√2π against ln α over the (k_l, H) points "
               "at k_s = 32, N = 1024 (λ_s = 32 Δx), its standard error scaled by the root of the reduced χ² when "
               "that exceeds 1; yes when abs(slope) > 3 standard errors, no otherwise")

_PERSSON_BANDS = (
    "at A/A0 = 0.01 and 0.1 per H, as a [low, high] band over Persson's γ = 0.4, 0.45, 0.5 beside the γ = 0.45 "
    "value, with the generator's expected spectrum and with each surface's own (measured) one, Persson's w(q) read "
    "at the middle of each shell's power (the continuum's midpoint rule); the mode-count cells k_l = 4 and 8 (k_s = "
    "2 k_l, 32 px per λ_s: scenes persson-modes-256 and -512) at A/A0 = 0.01, expected spectrum, with the seed "
    "standard error of the measured value; the discretisation's sensitivity at γ = 0.45, expected spectrum, A/A0 = "
    "0.01: w(q) with the whole shell's power, mode by mode, and the continuum integral over the ideal power law; yes "
    "when every band and every sensitivity printed lies within [0.9, 1.1] and no mode-count cell is pending, partly "
    "when at least half of the γ = 0.45 values are within (the γ band, the spectrum, the mode count or the "
    "discretisation flips the verdict), no otherwise")

RULES: dict[str, Rule] = {
    "Q1a: the CEL holds toward full contact": Rule(
        "pooled mean A/A0 over all surfaces against the CEL with the scene's own pooled-H fit; the A/A0 where "
        "abs(A_CEL/A − 1) first exceeds 5 % (and, as the sensitivity, 4 %), interpolated linearly in A/A0 between "
        "the two load steps that bound it; yes when both crossings are at A/A0 ≥ 0.5, partly when the 5 % crossing "
        "is at ≥ 0.11 (the fit window), no otherwise", _cel),
    "Q1b: Persson's erf curve holds toward full contact": Rule(
        "A_Persson/A − 1 at the steps where the pooled mean crosses A/A0 = 0.01, 0.1, 0.5, 0.9 (interpolated in "
        "ln p̄); yes when within 5 % at all four, partly when at the two largest, no otherwise", _persson_area),
    "Q1c: full contact begins at the exact full-contact load": Rule(
        "per surface, A/A0 = 1 exactly at the steps with p0 > p_fc and < 1 at those below; yes when so for every "
        "surface, no otherwise", _onset),
    "Q1d: the approach to full contact is H-independent": Rule(
        "at each step with pooled mean A/A0 in [0.9, 1), the largest z = abs(m_i − m_j) / √(s_i² + s_j²) of the "
        "H means of 1 − A/A0 (s: their standard errors over seeds); yes when z ≤ 3 at every such step, partly at "
        "at least half, no otherwise", _h_independent),
    "Q1e: Persson's erfc(√2 p̄) gives 1 − A/A0 near full contact": Rule(
        "(1 − A/A0) / erfc(√2 p̄) of the pooled mean at the steps with A/A0 in [0.9, 1); yes when it stays "
        "within [0.5, 2] at every such step, no otherwise", _tail),
    "Q4a: Persson's mean gap": Rule("seed-mean gap / Persson's " + _PERSSON_BANDS, _ratio_bands),
    "Q4b: Persson's contact stiffness": Rule(
        "seed-mean K = −dp0/dū over Persson's −dp0/dū " + _PERSSON_BANDS, _ratio_bands),
    "Q4c: Persson's P(p)": Rule(
        "L1 distance Σ abs(P − P_Persson) Δp / Σ P Δp of the pooled distribution at the steps nearest A/A0 = 0.01, "
        "0.1, 0.5, 0.9; yes when ≤ 0.1 at every load, partly at at least half, no otherwise", _distance),
    "Q4d: the contact area percolates at A/A0 ≈ 0.42": Rule(
        "per surface and definition, the A/A0 bracket of the two load steps between which the contact first "
        "percolates: the first step where a 4-connected cluster wraps the periodic cell (cluster_wrapping) in x or "
        "y, in x, in y, or one cluster in both directions; a definition's threshold is the mean of its bracket "
        "midpoints; the threshold compared is the one-direction one of Dapp et al. (the leakage across the cell "
        "stops), the mean of the in-x and in-y thresholds, ± u, u the largest of half the range of the four "
        "definitions' thresholds, the standard error of the midpoints over surfaces (the seed spread) and half the "
        "widest bracket (the step spacing); without wrapping data, where the largest cluster's share of the contact "
        "last crosses half (a proxy; u without the definitions); yes when abs(threshold − 0.42) ≤ 2u with u ≤ 0.01, "
        "partly when abs(threshold − 0.42) ≤ max(2u, 0.05), no otherwise", _percolation),
    "Q2a: κ depends on α at fixed resolution (pixel-counted area)": Rule(_SLOPE_RULE, _slope),
    "Q2b: κ depends on α at fixed resolution (perimeter-corrected area)": Rule(_SLOPE_RULE, _slope),
    "Q2c: BGT and Greenwood give κ at the surfaces' own α": Rule(
        "each model's κ(0.05) at each (k_l, H) point's seed-mean α against the seed-mean pixel-counted κ(0.05); "
        "yes when one model is within 5 % at every point, partly at at least half of them, no otherwise", _models),
    "Q2d: at equal α, λ_l = L/8 and L/4 cells (N = 2048) follow the N = 1024 trend": Rule(
        "seed-mean κ(0.05)/√2π of each (k_l, H) point of the kappa-alpha scene (k_s = 64, N = 2048: 32 pixels "
        "per λ_s) against the weighted line κ = a + b ln α through the paper grid's λ_s = 32 Δx points, z = "
        "(κ − line) / √(sem² + s²) with s those points' scatter about the line; yes when abs(z) ≤ 2 for every "
        "point (the trend is α, not the cells' representativity), partly for at least half, no otherwise",
        _on_trend),
    "Q2e: κ falls linearly in ln α over the whole range, N = 1024 to 4096 at 32 px per λ_s": Rule(
        "weighted least-squares fits of the seed-mean κ(0.05)/√2π against ln α (slope) and against ln α and (ln α)² "
        "(curvature: the (ln α)² coefficient) over every (k_l, k_s, H) point at 32 pixels per λ_s (paper grid k_s = "
        "32, kappa-alpha k_s = 64, kappa-alpha-4096 k_s = 128), and again over the points below and above α = 3 "
        "(none lies between 2.8 and 3.7), standard errors scaled by the root of the reduced χ² when that exceeds 1; "
        "α is each point's seed mean of its surfaces' measured α = m0 m4 / m2²; the α ≥ 3 line is compared with the "
        "point at the largest α by z = (κ − line) / √(s² + σ_line²), s the point's seed error scaled as the fit's; "
        "yes when over all points abs(slope) > 3 standard errors and abs(curvature) ≤ 2 (a fall linear in ln α "
        "throughout), partly when all points bend (abs(curvature) > 2 standard errors) but above α = 3 abs(slope) > "
        "3 and abs(curvature) ≤ 2 standard errors (the bend lies below α = 3, the fall is linear in ln α above it), "
        "no otherwise; sensitivities, the same fits of the perimeter-corrected κ and with the α of the generator's "
        "expected lattice spectrum: the verdict when all three give it, partly when they differ", _bend),
    "Q3a: κ is the same on L and 2L cells": Rule(
        "z = (κ_2L − κ_L) / √(s_L² + s_2L²) of the seed means (s: standard errors) at A/A0 = 0.01, 0.05, 0.1 per "
        "H; yes when abs(z) ≤ 2 at every point, partly at at least half, no otherwise", _same_kappa),
    "Q3b: κ's seed scatter halves on a 2L cell": Rule(
        "ratio of the seed standard deviations of κ(0.05), 2L over L, with its 95 % interval (F distribution); "
        "yes when the interval contains 0.5 and lies below 1 for every H, partly when it contains 0.5 for every "
        "H, no otherwise", _halves),
}


def row(question: str, comparison: str, measured: str) -> dict:
    """One judged row (``paper`` is the comparison column, ``ours`` the measured one)."""
    return judged_row(question, comparison, measured, RULES)

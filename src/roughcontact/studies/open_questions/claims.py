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
    [(upto,)] = floats_matching(rf"within 5 % up to A/A0 = ({NUMBER})", measured)
    return "yes" if upto >= 0.5 else "partly" if upto >= 0.11 else "no"


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


def _ratios(comparison: str, measured: str) -> str:
    ratios = [r for r, _ in floats_matching(rf"({NUMBER}) \(H=({NUMBER})\)", measured)]
    return _share(float(np.mean([0.9 <= r <= 1.1 for r in ratios])))


def _distance(comparison: str, measured: str) -> str:
    d = [v for _, v in floats_matching(rf"A/A0 = ({NUMBER}): ({NUMBER})", measured)]
    return _share(float(np.mean([v <= 0.1 for v in d])))


def _percolation(comparison: str, measured: str) -> str:
    [(m, _)] = floats_matching(rf"at A/A0 = ({NUMBER}) ± ({NUMBER})", measured)
    return "yes" if abs(m - 0.42) <= 0.05 else "no"


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

RULES: dict[str, Rule] = {
    "Q1a: the CEL holds toward full contact": Rule(
        "pooled mean A/A0 over all surfaces against the CEL with the scene's own pooled-H fit; yes when within 5 % "
        "at every step up to A/A0 ≥ 0.5, partly when up to at least 0.11 (the fit window), no otherwise", _cel),
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
    "Q4a: Persson's mean gap": Rule(
        "seed-mean gap / Persson's (γ = 0.45, the surfaces' own spectrum) at A/A0 = 0.01 and 0.1 per H; yes "
        "when every ratio is within [0.9, 1.1], partly when at least half are, no otherwise", _ratios),
    "Q4b: Persson's contact stiffness": Rule(
        "seed-mean K = −dp0/dū over Persson's −dp0/dū at A/A0 = 0.01 and 0.1 per H; yes when every ratio is "
        "within [0.9, 1.1], partly when at least half are, no otherwise", _ratios),
    "Q4c: Persson's P(p)": Rule(
        "L1 distance Σ abs(P − P_Persson) Δp / Σ P Δp of the pooled distribution at the steps nearest A/A0 = 0.01, "
        "0.1, 0.5, 0.9; yes when ≤ 0.1 at every load, partly at at least half, no otherwise", _distance),
    "Q4d: the contact area percolates at A/A0 ≈ 0.42": Rule(
        "per surface, the A/A0 at which the largest contact cluster last crosses half the contact area "
        "(a proxy of the spanning cluster), mean ± standard error; yes when within 0.05 of 0.42, no otherwise",
        _percolation),
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

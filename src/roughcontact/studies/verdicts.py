"""The reproduction's verdicts, each derived from the numbers its claim row prints by the rule it prints.

A claim row (:mod:`roughcontact.studies.reproduction`) is ``claim, paper, ours, verdict, test``. Its
verdict is not computed beside the text: :func:`judge` reads the printed ``paper`` and ``ours``
columns back and applies the claim's :class:`Rule`, whose ``test`` text is the one printed. So a
verdict can never be looser (or stricter) than the rule beside it, and a published table can be
checked from its text alone (:func:`check_table`; tests/test_reproduction.py does so for every
published claim table).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass

NUMBER = r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?"
SQRT_2PI = math.sqrt(2 * math.pi)
SQRT_8_PI = math.sqrt(8 / math.pi)


@dataclass(frozen=True)
class Rule:
    """A claim's printed rule (``test``) and its verdict from the row's printed ``paper`` and ``ours``."""

    test: str
    verdict: Callable[[str, str], str]


def floats_matching(pattern: str, text: str) -> list[tuple[float, ...]]:
    """Every match of ``pattern`` in ``text``, its groups as floats."""
    return [tuple(float(g) for g in m.groups()) for m in re.finditer(pattern, text)]


def _count(fraction: float) -> str:
    """Reproduced for all, partly for at least half, not otherwise."""
    return "reproduced" if fraction == 1 else "partly" if fraction >= 0.5 else "not"


# ------------------------------------------------------------------------------- representativity
def _threshold(paper: str, ours: str) -> str:
    eps = floats_matching(rf"({NUMBER}) \(k_l=({NUMBER})\)", ours.split(";")[0])
    floor = floats_matching(rf"noise floor ({NUMBER})", ours)[0][0]
    values = [v for v, _ in eps]
    falls = all(b <= 1.05 * a for a, b in zip(values, values[1:], strict=False))
    reached = [k for v, k in eps if v <= 2 * floor]
    if not falls:
        return "not"
    return "reproduced" if reached and reached[0] in (8.0, 16.0) else "partly"


def _ks_weaker(paper: str, ours: str) -> str:
    [(ks,)] = floats_matching(rf"at fixed k_l: ({NUMBER})", ours)
    [(kl,)] = floats_matching(rf"over k_l: ({NUMBER})", ours)
    return "reproduced" if ks < 0.5 * kl else "not"


def _ks_falls(paper: str, ours: str) -> str:
    drops = floats_matching(rf"Δ = ({NUMBER}) ± ({NUMBER})", ours)
    return _count(sum(d > 2 * e for d, e in drops) / len(drops))


# ------------------------------------------------------------------------------------------ kappa
def _h_spread(paper: str, ours: str) -> str:
    rep, nonrep = (v for (v,) in floats_matching(rf"({NUMBER}) % at", ours))
    return "reproduced" if rep < 0.5 * nonrep else "partly" if rep < nonrep else "not"


def _h_direction(paper: str, ours: str) -> str:
    pairs = floats_matching(rf"\): ({NUMBER}) → ({NUMBER})", ours)
    return _count(sum(b < a for a, b in pairs) / len(pairs))


def _scatter(paper: str, ours: str) -> str:
    by_kl = [v for v, _ in floats_matching(rf"({NUMBER}) % \(k_l=({NUMBER})\)", ours)]
    by_h = [v for v, _ in floats_matching(rf"({NUMBER}) % \(H=({NUMBER})\)", ours)]
    n = (by_kl[-1] < by_kl[0]) + (by_h[-1] > by_h[0])
    return "reproduced" if n == 2 else "partly" if n == 1 else "not"


def _kl_rises(paper: str, ours: str) -> str:
    rows = floats_matching(rf"({NUMBER}) ± ({NUMBER}) \(k_l=({NUMBER})\)", ours)
    k, e = [r[0] for r in rows], [r[1] for r in rows]
    steps = [b - a for a, b in zip(k, k[1:], strict=False)]
    if all(s > 0 for s in steps):
        return "reproduced"
    errs = [math.hypot(a, b) for a, b in zip(e, e[1:], strict=False)]
    plateau = k[-1] - k[0] > 2 * math.hypot(e[-1], e[0]) and all(s > -2 * d for s, d in zip(steps, errs,
                                                                                            strict=True))
    return "partly" if plateau else "not"


def _not_confined(paper: str, ours: str) -> str:
    (low, high), = floats_matching(rf"from ({NUMBER}) to ({NUMBER})", ours)
    return "reproduced" if high > SQRT_2PI or low < SQRT_8_PI else "not"


def _decreasing(paper: str, ours: str) -> str:
    (pct,), = floats_matching(rf"for ({NUMBER}) % of", ours)
    return _count(pct / 100)


def _persson(paper: str, ours: str) -> str:
    (low,), = floats_matching(rf"any load step: ({NUMBER})", ours)
    return "reproduced" if low > SQRT_8_PI else "not"


def _asperity(paper: str, ours: str) -> str:
    [(bgt,)], [(gw,)] = floats_matching(rf"BGT ({NUMBER}) %", ours), floats_matching(rf"Greenwood ({NUMBER}) %", ours)
    worst = min(bgt, gw)
    return "reproduced" if worst >= 90 else "partly" if worst >= 50 else "not"


# -------------------------------------------------------------------------------------------- CEL
def _paper_range(text: str) -> tuple[float, float]:
    """The paper's value or range as printed: ``(v ± d)``, ``v ± d``, ``∈ [a, b]`` or ``v``."""
    if m := re.search(rf"\[({NUMBER}), ({NUMBER})\]", text):
        return float(m.group(1)), float(m.group(2))
    if m := re.search(rf"({NUMBER}) ± ({NUMBER})", text):
        v, d = float(m.group(1)), float(m.group(2))
        return v - d, v + d
    v = float(re.search(NUMBER, text).group(0))
    return v, v


def _constant(paper: str, ours: str) -> str:
    """Reproduced when the data constrain the constant and the paper's range overlaps our interval."""
    lo, hi = floats_matching(rf"interval \[({NUMBER}), ({NUMBER})\]", ours)[0]
    plo, phi = _paper_range(paper)
    return "reproduced" if "not constrained" not in ours and lo <= phi and plo <= hi else "not"


def _rough_cel(paper: str, ours: str) -> str:
    papers = dict(zip(("κ", "μ", "β"), re.split(r", (?=[μβ] )", paper), strict=True))
    verdicts = [_constant(papers[part.split(" ")[0]], part) for part in ours.split("; ") if part[:1] in papers]
    return "reproduced" if set(verdicts) == {"reproduced"} else "not" if set(verdicts) == {"not"} else "partly"


def _final_area(paper: str, ours: str) -> str:
    (mean,), = floats_matching(rf"^({NUMBER}) %", ours)
    return "reproduced" if 7 <= mean <= 14 else "not"


CEL_RULE = ("reproduced when the data constrain the constant and the paper's value (or range) overlaps our 95 % "
            "bootstrap interval over seeds, not otherwise (the paper's fit: κ from κ(A), then μ, β from ∂p̄/∂p0, "
            "window A/A0 ∈ [0.01, 0.11])")

#: Every claim's rule, by the claim's text.
RULES: dict[str, Rule] = {
    "representativity grows with k_l up to k_l ≈ 8–16": Rule(
        "mean over k_s, H and seeds of the scale-free ε_σ against the noise floor, ε_σ of i.i.d. Gaussian heights "
        "with the same bins and number of points (mean of 30 draws); threshold = first k_l with ε_σ within 2× the "
        "floor; reproduced when ε_σ falls with k_l (each value ≤ 1.05× the one before) and the threshold is 8 or "
        "16, partly when it falls but the threshold is elsewhere or not reached, not when it does not fall",
        _threshold),
    "k_s has a weaker effect than k_l (for k_s ≫ k_l)": Rule(
        "(max − min)/mean of ε_σ over k_s, median over k_l; reproduced when below half the same spread over k_l, "
        "not otherwise", _ks_weaker),
    "ε decreases with k_s for all k_l (appendix)": Rule(
        "per k_l, Δ = ε_σ at the smallest k_s minus ε_σ at the largest (seed and H means) ± its standard error over "
        "seeds; reproduced when Δ > 2 s.e. for every k_l, partly for at least half of them, not otherwise",
        _ks_falls),
    "κ(A/A0) independent of H for representative smooth surfaces, H-dependent otherwise": Rule(
        "(max − min)/mean over H of the seed-mean κ at A/A0 = 0.05; reproduced when the representative spread is "
        "below half the non-representative one, partly when below it, not otherwise", _h_spread),
    "higher H gives smaller κ for non-representative (λ_l > L/16) or rough (λ_s < 32 Δx) surfaces": Rule(
        "every (k_l, k_s) family but the representative smooth one: κ(0.05) at the largest H below that at the "
        "smallest; reproduced in every family, partly in at least half, not otherwise", _h_direction),
    "seed scatter falls with k_l and rises with H": Rule(
        "coefficient of variation over seeds, averaged over the other parameters; compares the ends: reproduced "
        "when both trends hold, partly when one does, not otherwise", _scatter),
    "κ rises as λ_l falls (k_l rises)": Rule(
        "seed-, H- and k_s-mean κ at A/A0 = 0.05 (± its standard error over seeds) increasing in k_l; partly "
        "when it rises from the smallest to the largest k_l by more than two standard errors and falls "
        "between neighbours by less than two (a plateau inside the seed scatter), not otherwise", _kl_rises),
    "κ is not confined between the Persson (√(8/π) ≈ 1.60) and BGT (√(2π) ≈ 2.51) asymptotes": Rule(
        "seed-mean κ at A/A0 = 0.01, 0.02, 0.05, 0.1: reproduced when its range reaches above √(2π) or below "
        "√(8/π) for some (k_l, k_s, H), not otherwise", _not_confined),
    "κ decreases with A/A0 over the observed range (up to ≈ 10 %)": Rule(
        "seed-mean κ at A/A0 = 0.01, 0.02, 0.05, 0.1 strictly decreasing, per (k_l, k_s, H); reproduced for every "
        "point, partly for at least half, not otherwise", _decreasing),
    "Persson's small-load asymptote (κ = √(8/π) ≈ 1.60) lies below all results": Rule(
        "every case's κ above √(8/π) at every load step (its A/A0 above Persson's linear limit); not otherwise",
        _persson),
    "BGT and Greenwood (α = 2) lie in the confidence interval of the non-representative λ_l = L results with "
    "H ≳ 0.5": Rule(
        "each model's A/A0(p0), with h' the cases' mean rms slope, within 1.96 s.d. over seeds of the seed-mean "
        "A/A0; reproduced at ≥ 90 % of the (k_s, H, step) points for both models, partly at ≥ 50 %, not otherwise",
        _asperity),
    "kappa = paper value (λ_l = L/16, λ_s = L/32, pooled H)": Rule(CEL_RULE, _constant),
    "mu = paper value (λ_l = L/16, λ_s = L/32, pooled H)": Rule(CEL_RULE, _constant),
    "beta = paper value (λ_l = L/16, λ_s = L/32, pooled H)": Rule(CEL_RULE, _constant),
    "CEL at λ_l = L/16, λ_s = L/128 (Fig. 3b caption)": Rule(
        CEL_RULE + ", for each constant; reproduced when all three are, not when none is, partly otherwise",
        _rough_cel),
    "A/A0 ≈ 10 % at the final load": Rule(
        "mean over cases within 7–14 %, not otherwise; the load is the config's p0/E* = 0.005, not the paper's "
        "printed 0.05, which contradicts its own ≈ 10 % (config/README.md)", _final_area),
}


def judge(claim: str, paper: str, ours: str, rules: dict[str, Rule] | None = None) -> str:
    """The verdict of ``claim`` by its rule (in ``rules``, default :data:`RULES`), from the printed texts."""
    rules = RULES if rules is None else rules
    if claim not in rules:
        raise KeyError(f"no verdict rule for claim {claim!r}: add one to the page's RULES")
    return rules[claim].verdict(paper, ours)


def check_table(markdown: str, rules: dict[str, Rule] | None = None) -> list[str]:
    """Rows of a published claim table whose verdict or printed rule disagrees with :data:`RULES`.

    ``pending`` rows (nothing measured yet) are skipped. Returns one line per disagreement.
    """
    rules = RULES if rules is None else rules
    problems = []
    for line in markdown.splitlines()[2:]:
        cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
        if len(cells) != 5:
            problems.append(f"not a claim row: {line!r}")
            continue
        claim, paper, ours, verdict, test = cells
        verdict = verdict.strip("*")
        if verdict == "pending":
            continue
        if claim not in rules:
            problems.append(f"{claim!r}: no rule")
            continue
        if test != rules[claim].test:
            problems.append(f"{claim!r}: the printed test is not the rule's")
        if (got := judge(claim, paper, ours, rules)) != verdict:
            problems.append(f"{claim!r}: printed verdict {verdict!r}, its rule on its numbers gives {got!r}")
    return problems


def row(claim: str, paper: str, ours: str, verdict: str, test: str) -> dict:
    """One row of a claim table."""
    return {"claim": claim, "paper": paper, "ours": ours, "verdict": verdict, "test": test}


def judged_row(claim: str, paper: str, ours: str, rules: dict[str, Rule] | None = None) -> dict:
    """A claim row whose verdict is its printed rule applied to its printed numbers (:func:`judge`)."""
    rules = RULES if rules is None else rules
    return row(claim, paper, ours, judge(claim, paper, ours, rules), rules[claim].test)

"""One group's fit: both estimators on the group's curves, and the bootstrap over whole seeds (or topographies).

``bootstrap_stderr`` and the percentile interval ``[ci_low, ci_high]`` come from resampling whole
seeds with replacement (stratified by H for the H-pooled fit) and refitting; the bootstrap
standard deviation is multiplied by ``sqrt(n / (n - 1))`` (``n`` seeds per H stratum). Groups with a
single seed per stratum get no bootstrap (NaN, ``n_boot_ok = 0``).
"""

from __future__ import annotations

import hashlib
import logging
import math
from collections.abc import Sequence

import numpy as np

from .estimators import CONSTANTS, PAPER_CEL, Curves, FitError, TooFewPoints, fit_joint, fit_paper

_log = logging.getLogger(__name__)


def _resample(c: Curves, rng: np.random.Generator) -> np.ndarray:
    """Seed indices drawn with replacement within each H stratum."""
    rows = []
    for label in np.unique(c.strata):
        idx = np.flatnonzero(c.strata == label)
        rows.append(idx[rng.integers(0, idx.size, idx.size)])
    return np.concatenate(rows)


def group_rng(rng_seed: int, k_l: float, k_s: float, label: str) -> np.random.Generator:
    """The bootstrap generator of one fit group: seeded by ``rng_seed`` and keyed by the group
    ``(k_l, k_s, label)``, so a group's resamples do not depend on which other groups exist."""
    # Keyed by the group, so a group's resamples do not depend on which other groups exist.
    key = f"{float(k_l)!r}|{float(k_s)!r}|{label}".encode()
    digest = int.from_bytes(hashlib.sha256(key).digest()[:8], "little")
    return np.random.default_rng(np.random.SeedSequence(entropy=int(rng_seed), spawn_key=(digest,)))


def _differing_stratum(curves: Curves):
    """The first stratum whose rows have different normalised load schedules ``p0 / (E* h')``, or None.

    That schedule is what the CEL is a function of: surfaces of different rms slope loaded
    relative to it (``load.relative_to: rms_slope``) share it, as seeds of one generated surface
    type share ``p0``.
    """
    normalised = curves.p0 / curves.hp[:, None]
    for lab in np.unique(curves.strata):
        sched = normalised[curves.strata == lab]
        if not np.allclose(sched, sched[0], rtol=1e-12, atol=0.0, equal_nan=True):
            return lab
    return None


def shared_schedule(curves: Curves) -> bool:
    """Whether every stratum of ``curves`` has one normalised load schedule (see :func:`_differing_stratum`)."""
    return _differing_stratum(curves) is None


def check_schedules(curves: Curves, who: Sequence[str]) -> None:
    """ValueError unless the rows of each stratum share one load schedule (the seed mean needs it).

    ``who[label]`` names the rows of stratum ``label`` in the message.
    """
    lab = _differing_stratum(curves)
    if lab is not None:
        raise ValueError(f"{who[lab]} have different load schedules p0/(E* h'), so their curves cannot be "
                         "averaged step by step; pass paper_average='none' (or 'auto', as the pipeline's fit does: "
                         "'none' where the schedules differ), or load them alike (in a scene: load.p_max with "
                         "load.relative_to: rms_slope, not load.target_area)")


class GroupFit:
    """One group's results: arrays over ``(estimator, constant)``, ``n_boot_ok`` over ``estimator``."""

    def __init__(self, n_methods: int):
        shape = (n_methods, len(CONSTANTS))
        self.value, self.stderr, self.bstd, self.clo, self.chi = (np.full(shape, np.nan) for _ in range(5))
        self.npts = np.zeros(shape, dtype=np.int64)
        self.nboot_ok = np.zeros(n_methods, dtype=np.int64)


def fit_group(curves: Curves, *, methods: Sequence[str], e_star: float, min_points: int,
               kappa_extrapolation: str, paper_average: str, n_boot: int, confidence: float,
               rng: np.random.Generator, on_insufficient: str, caller: str, where: str, window) -> GroupFit:
    """Every estimator on one group's curves, then the bootstrap over its rows (seeds, topographies).

    Shared by :func:`fit_cel` (a call per group) and :func:`fit_topographies` (one call); ``rng``
    draws the resamples; ``caller``, ``where`` and ``window`` (as passed) name the group in errors.
    """
    out = GroupFit(len(methods))
    q = 100.0 * (1.0 - float(confidence)) / 2.0

    def run(method, c, guess):
        if method == "paper":
            return fit_paper(c, min_points, kappa_extrapolation, paper_average == "seeds")
        return fit_joint(c, e_star, min_points, guess)

    full = {}
    for m, method in enumerate(methods):
        guess = np.array([PAPER_CEL[c][0] for c in CONSTANTS])
        if method == "joint" and "paper" in full:
            # The paper route is a good, cheap starting point when it is sane.
            pv = full["paper"][0]
            if np.all(np.isfinite(pv)) and 0 < pv[1] < 1 and pv[0] > 0 and pv[2] > 0:
                guess = pv
        try:
            full[method] = run(method, curves, guess)
        except FitError as err:
            if on_insufficient == "raise":
                raise ValueError(
                    f"{caller} ({method}) at {where} with window={window!r}: {err}; "
                    "widen `window`, add load steps, or pass on_insufficient='nan'"
                ) from None
            # The reason goes to the job's log: a NaN in cel.csv alone does not say why.
            _log.warning("no CEL fit (%s) at %s, window %s: %s%s", method, where, tuple(window), err,
                         "; widen fit.window or add load steps (contact.load.n_steps)"
                         if isinstance(err, TooFewPoints) else "")
            continue
        out.value[m], out.stderr[m], out.npts[m] = full[method]

    # A stratum with one seed has no seed-to-seed information: the bootstrap
    # would report zero scatter, so it is skipped (NaN, n_boot_ok = 0).
    n_min = min(np.bincount(curves.strata)[np.unique(curves.strata)]) if curves.n_seeds else 0
    if n_min < 2:
        return out
    # The bootstrap variance of a mean over n clusters is (n-1)/n times the
    # unbiased one; rescaling by n/(n-1) matters with the paper's 12 seeds.
    inflate = math.sqrt(n_min / (n_min - 1.0))
    boot = {method: np.full((n_boot, 3), np.nan) for method in full}
    for b in range(n_boot):
        sample = curves.take(_resample(curves, rng))
        for method in full:
            try:
                boot[method][b] = run(method, sample, full[method][0])[0]
            except (FitError, np.linalg.LinAlgError):
                pass  # counted through n_boot_ok
    _summarise_bootstrap(out, boot, methods, inflate, q)
    return out


def _summarise_bootstrap(out: GroupFit, boot: dict, methods: Sequence[str], inflate: float, q: float) -> None:
    """Each method's finite draws into ``out``: their count, inflated std and ``q``-percentile interval."""
    for m, method in enumerate(methods):
        if method not in boot:
            continue
        draws = boot[method][np.all(np.isfinite(boot[method]), axis=1)]
        out.nboot_ok[m] = draws.shape[0]
        if draws.shape[0] >= 2:
            out.bstd[m] = inflate * draws.std(axis=0, ddof=1)
            out.clo[m] = np.percentile(draws, q, axis=0)
            out.chi[m] = np.percentile(draws, 100.0 - q, axis=0)

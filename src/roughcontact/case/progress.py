"""A case's progress as log text: one line per load step, with what is left (:func:`step_logger`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def duration_text(seconds: float) -> str:
    """A duration [s] as log text: ``"42 s"``, ``"3 min 05 s"``, ``"1 h 23 min"``."""
    minutes, secs = divmod(round(seconds), 60)
    hours, minutes = divmod(minutes, 60)
    if hours:
        return f"{hours} h {minutes:02d} min"
    return f"{minutes} min {secs:02d} s" if minutes else f"{secs} s"


def eta(seconds: Sequence[float], total: int) -> str:
    """What is left of a job of ``total`` equal parts after those timed in ``seconds``, as log text.

    The pace is that of the last (up to) five parts: load steps slow down as the contact grows,
    so the recent pace predicts better than the mean. ``"done"`` when nothing is left.

    Examples
    --------
    >>> eta([2.0, 4.0], 5)
    'about 9 s left (3 of 5 to go)'
    """
    left = total - len(seconds)
    if left <= 0:
        return "done"
    recent = list(seconds)[-5:]
    return f"about {duration_text(left * sum(recent) / len(recent))} left ({left} of {total} to go)"


def step_logger(log, n_steps: int):
    """One log line per load step as it goes, with what is left (None without a log).

    ``progress(step, p0, area, iterations, converged, seconds)`` for the solver's ``progress``. A batch's steps
    report per-case arrays: its line gives the range of A/A0 over the cases, their number, the most iterations
    of any and how many did not converge (:data:`roughcontact.pipeline.progress.STEP_LINE` reads both lines).
    """
    if log is None:
        return None
    spent = []

    def progress(step, p0, area, iterations, converged, seconds):
        spent.append(seconds)
        if np.ndim(area) == 0:
            log.info("step %d/%d: p0 = %.6g, A/A0 = %.6g, %d iterations, %.2f s%s; %s", step, n_steps, p0, area,
                     iterations, seconds, "" if converged else ", NOT converged", eta(spent, n_steps))
            return
        bad = int(np.size(converged) - np.count_nonzero(converged))
        log.info("step %d/%d: p0 = %.6g, A/A0 = %.6g .. %.6g, %d cases, %d iterations, %.2f s%s; %s",
                 step, n_steps, p0, np.min(area), np.max(area), np.size(area), np.max(iterations), seconds,
                 f", {bad} NOT converged" if bad else "", eta(spent, n_steps))

    return progress

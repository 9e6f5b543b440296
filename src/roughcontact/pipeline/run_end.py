"""What the workflow does when a Snakemake run ends: let the process exit as soon as its work is done.

Snakemake's job-rate limit (``max-jobs-per-timespan``; ``10000/1m`` in ``profiles/default``, chosen
so that job selection runs once a minute, not once a second) re-evaluates the waiting jobs from a
:class:`threading.Timer` started after every round of job selection, one timespan later. The timer is
not a daemon thread, so the interpreter waits for the last one before it exits: every local run,
however short, lingered up to a minute after its last job (measured 2026-11-28: the ``tiny`` test
scene, 42 s of jobs, 104 s until the command returned; 43 s with the timer cancelled). When the run
has ended (Snakemake's ``onsuccess`` / ``onerror`` hooks, after its scheduler has returned) no job
is left to select, and :func:`cancel_job_rate_timers` cancels those timers.
"""

from __future__ import annotations

import threading

#: Where the functions of the timers :func:`cancel_job_rate_timers` cancels are defined.
SNAKEMAKE_SCHEDULER_MODULE = "snakemake.scheduling"


def cancel_job_rate_timers() -> int:
    """Cancel the job re-evaluation timers Snakemake's scheduler left pending; returns how many.

    Only a :class:`threading.Timer` whose function comes from Snakemake's scheduling package is
    cancelled (its only effect would be one more round of job selection, with no job left); any
    other timer of the process is left to run.

    Examples
    --------
    >>> cancel_job_rate_timers()  # no Snakemake scheduler in this process
    0
    """
    cancelled = 0
    for thread in threading.enumerate():
        function = getattr(thread, "function", None)
        if isinstance(thread, threading.Timer) and \
                getattr(function, "__module__", "").startswith(SNAKEMAKE_SCHEDULER_MODULE):
            thread.cancel()
            cancelled += 1
    return cancelled

"""What the workflow does when a Snakemake run ends: say where the result is, and let the process exit as soon
as its work is done.

A run that succeeds ends with three lines (:func:`where_it_is`): the report's result line, the figures folder
and the command that builds the HTML report, so that a user does not have to find them under Snakemake's
``Complete log(s): ...``.

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

import re
import threading
from pathlib import Path

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


#: LaTeX of the report's result line, as a terminal shows it.
PLAIN_MATHS = {r"\lambda": "λ", r"\kappa": "κ", r"\mu": "μ", r"\beta": "β", r"\sqrt": "√", r"\pi": "π",
               r"\bar": "", r"\mathrm": "", "{": "", "}": "", r"\,": " "}


def plain_text(rst: str) -> str:
    """One paragraph of the report's reStructuredText as a terminal line: maths as its symbols, no markup.

    Examples
    --------
    >>> plain_text(r"**Result** (:math:`\\lambda_l = L/16`, 3 seeds): κ/√(2π) = 1.06 [1.03, 1.16] \\*.")
    'Result (λ_l = L/16, 3 seeds): κ/√(2π) = 1.06 [1.03, 1.16] *.'
    """
    def maths(match: re.Match) -> str:
        text = match.group(1)
        for latex, shown in PLAIN_MATHS.items():
            text = text.replace(latex, shown)
        return text

    text = re.sub(r":math:`([^`]*)`", maths, rst)
    text = text.replace("**", "").replace("``", "").replace(r"\*", "*")
    return " ".join(text.split())


def where_it_is(results: str | Path, scene: str, drawn: int | None = None) -> list[str]:
    """What a finished run tells its user last: the result, where the figures are, how to build the report.

    ``results`` is the scene's output folder (``results/{scene}``). Three lines: the report's result line
    (the first paragraph of ``report/result.rst``, :func:`plain_text`; an adhesive scene's says its pull-off
    table is in the report), the figures folder with its count of figures, and the ``snakemake --report``
    command. A line whose file the run has not made yet (a run that made one file) says so instead.
    ``drawn`` is the number of figures the scene draws (``None``: unknown): a scene that draws none says so,
    not that its figures are yet to come.

    Examples
    --------
    >>> where_it_is("results/nosuch", "nosuch")[2].split(" (")[0]
    'Report: snakemake --report report.html --config scene=nosuch'
    """
    results = Path(results)
    result_file = results / "report" / "result.rst"
    if result_file.is_file():
        text = result_file.read_text(encoding="utf-8")
        result = plain_text(text.strip().split("\n\n")[0])
        if "list-table" in text:  # an adhesive scene's pull-off table
            result = result.rstrip(".") + ": its table is in the report."
    else:
        result = f"Result: not made by this run (the whole scene makes it: snakemake -j2 --config scene={scene})"
    figures = sorted((results / "figures").glob("*.png")) if (results / "figures").is_dir() else []
    if figures:
        where = f"Figures: {results / 'figures'}/ ({len(figures)} figures, each as PNG and PDF with its caption)"
    elif drawn == 0:
        where = "Figures: none (this scene draws no figure)"
    else:
        where = f"Figures: none yet under {results / 'figures'}/"
    report = (f"Report: snakemake --report report.html --config scene={scene} (one HTML file: the result, every "
              "figure with its caption, the scene's tables, the run's provenance)")
    return [result, where, report]

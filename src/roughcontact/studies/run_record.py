"""The run record of a scene: what ran, where, when and at what cost, for the report's provenance section.

The report's summary (:func:`roughcontact.studies.report.summary_rst`) holds what the results depend on and
is byte-identical on a rerun. This record describes the run itself: the package version and git commit
(flagged when the tracked files differed from it), the Python and library versions (numpy, scipy, pyFFTW
and the FFTW it wraps, ...), the host, the date and the total CPU time of the run's jobs
(:mod:`roughcontact.pipeline.runcost`). A rerun on another day or machine writes other bytes: that is
what it records. The ``report_run`` rule writes it last, after every other output of the scene, to
``results/{scene}/report/run.rst``.
"""

from __future__ import annotations

import datetime
import importlib.metadata
import os
import platform
import re
from collections.abc import Mapping
from pathlib import Path

from ..pipeline.runcost import run_cost

#: Distributions whose versions the record gives, in this order, after Python's.
LIBRARIES = ("numpy", "scipy", "pyFFTW", "xarray", "netCDF4", "matplotlib", "snakemake", "docutils")

#: What a version is called when the distribution is not installed or does not say.
MISSING = "not installed"


def fftw_version() -> str:
    """The version of the FFTW library pyFFTW wraps, from its wisdom header (``"unknown"`` without pyFFTW)."""
    try:
        import pyfftw
    except ImportError:
        return "unknown"
    match = re.match(rb"\(fftw-([0-9][^ ]*) ", pyfftw.export_wisdom()[0])
    return match.group(1).decode() if match else "unknown"


def library_versions() -> dict[str, str]:
    """``{name: version}``: Python, each of :data:`LIBRARIES` (:data:`MISSING` if absent) and FFTW."""
    out = {"Python": platform.python_version()}
    for name in LIBRARIES:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = MISSING
    out["FFTW"] = fftw_version()
    return out


def total_cpu(results: str | Path) -> tuple[float, int, int]:
    """``(cpu_seconds, jobs, sampled)``: the CPU time of every finished job of the run in ``results``.

    ``sampled`` counts the jobs whose CPU is Snakemake's sample, a lower bound
    (:func:`roughcontact.pipeline.runcost.run_cost`).
    """
    costs = run_cost(results)
    return (sum(c.cpu_total for c in costs), sum(c.jobs for c in costs), sum(c.sampled for c in costs))


def cpu_text(seconds: float, jobs: int, sampled: int) -> str:
    """The run's CPU time as a reader reads it: ``"12.3 s"``, ``"4.5 min"`` or ``"2.1 h"``, with its job count."""
    value = (f"{seconds:.3g} s" if seconds < 120 else f"{seconds / 60:.3g} min" if seconds < 7200
             else f"{seconds / 3600:.3g} h")
    bound = "at least " if sampled else ""
    note = f"; {sampled} of them sampled by Snakemake, a lower bound" if sampled else ""
    return f"{bound}{value} over {jobs} job{'s' if jobs != 1 else ''}{note}"


def run_record_rst(*, version: str, commit: str, versions: Mapping[str, str], host: str,
                   when: datetime.datetime, cpu: str) -> str:
    """The record as reStructuredText: a ``Provenance`` section of one bulleted list.

    Parameters
    ----------
    version, commit : str
        The package version and :func:`roughcontact.studies.report.git_commit` of the code.
    versions : mapping
        :func:`library_versions`.
    host : str
        The machine's name (``platform.node()``) and what it is.
    when : datetime.datetime
        When the record was written (timezone-aware), given to the minute in UTC.
    cpu : str
        :func:`cpu_text` of the run.
    """
    if when.tzinfo is None:
        raise ValueError("the date must be timezone-aware")
    dirty = commit.endswith("(uncommitted changes)")
    tree = ("**uncommitted changes**: the tracked files differed from this commit" if dirty
            else "unknown (not a git checkout)" if commit == "unknown" else "clean")
    libs = ", ".join(f"{name} ``{v}``" for name, v in versions.items())
    lines = [
        f"- roughcontact version: ``{version}``",
        f"- git commit: ``{commit.removesuffix(' (uncommitted changes)')}``",
        f"- working tree: {tree}",
        f"- libraries: {libs}",
        f"- host: ``{host}``",
        f"- run recorded: {when.astimezone(datetime.UTC):%Y-%m-%d %H:%M} UTC",
        f"- total CPU time of the run's jobs: {cpu} (``python -m roughcontact.pipeline.runcost`` gives it per rule)",
    ]
    title = "Provenance"
    return f"{title}\n{'-' * len(title)}\n\n" + "\n".join(lines) + "\n"


def host_text() -> str:
    """This machine's name and platform, e.g. ``"node12 (Linux-6.1-x86_64, 16 CPUs)"``."""
    return f"{platform.node() or 'unknown'} ({platform.platform(terse=True)}, {platform.machine()}, " \
           f"{os.cpu_count()} CPUs)"

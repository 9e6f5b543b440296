"""CF conformance of written NetCDF files: ``cfchecks`` (cfchecker) where it runs, else the same checks here.

cfchecker (``pip install cfchecker``) needs the UDUNITS-2 C library of the system (``apt-get install
libudunits2-0``, or conda's ``udunits2``), which pip cannot install, so it is no test extra: where its
``cfchecks`` command runs, :func:`cf_problems` runs it (offline, with empty standard-name, area-type
and region tables: the files use none of them, and a ``standard_name`` would be reported as unknown);
elsewhere it runs :func:`own_checks`, the checks that cfchecker 4.1 found failing in these files and
those around them, with UDUNITS-2 through ``cf_units`` (whose wheels bundle it).
"""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
from functools import cache
from pathlib import Path

import netCDF4
import numpy as np
from cf_units import Unit

#: The empty tables cfchecks is given instead of downloading the current ones from cfconventions.org.
TABLES = {
    "-s": "<standard_name_table><version_number>0</version_number><last_modified>none</last_modified>"
          "</standard_name_table>",
    "-a": "<area_type_table><version_number>0</version_number><date>none</date></area_type_table>",
    "-r": "<standardized_region_list><version_number>0</version_number><date>none</date></standardized_region_list>",
}


@cache
def cfchecks_command() -> str | None:
    """The ``cfchecks`` command if it is installed and starts (it fails at import without libudunits2)."""
    here = Path(sys.executable).parent / "cfchecks"
    command = str(here) if here.exists() else shutil.which("cfchecks")
    if command is None:
        return None
    res = subprocess.run([command, "--help"], capture_output=True, text=True, timeout=120)
    return command if res.returncode == 0 else None


def run_cfchecks(paths, tables_dir: Path) -> dict[Path, list[str]]:
    """The ERROR and WARN lines ``cfchecks`` gives for each of ``paths`` (CF version from the files).

    Raises ``AssertionError`` when cfchecks fails to check a file (a crash, a FATAL message) or
    when its counts disagree with its messages.
    """
    tables_dir.mkdir(parents=True, exist_ok=True)
    options = []
    for flag, xml in TABLES.items():
        table = tables_dir / f"table{flag}.xml"
        table.write_text(f'<?xml version="1.0"?>\n{xml}\n')
        options += [flag, str(table)]
    paths = [Path(p) for p in paths]
    res = subprocess.run([cfchecks_command(), *options, *map(str, paths)], capture_output=True, text=True,
                         timeout=600)
    out = res.stdout + res.stderr
    assert "Traceback" not in out and "FATAL" not in out and "aborted" not in out, out[-4000:]
    sections = re.split(r"^CHECKING NetCDF FILE: (.*)$", out, flags=re.M)[1:]
    found = {}
    for name, text in zip(sections[::2], sections[1::2], strict=True):
        lines = [line for line in text.splitlines() if line.startswith(("ERROR:", "WARN:"))]
        counts = re.search(r"ERRORS detected: (\d+)\s+WARNINGS given: (\d+)", text)
        assert counts, text
        assert int(counts[1]) == sum(x.startswith("ERROR") for x in lines), text
        assert int(counts[2]) == sum(x.startswith("WARN") for x in lines), text
        found[Path(name.strip())] = lines
    assert sorted(found) == sorted(paths), f"cfchecks reported on {sorted(found)}, not {sorted(paths)}"
    return found


def _units_problem(units) -> str | None:
    if not isinstance(units, str):
        return f"units {units!r} is not a string"
    try:
        unit = Unit(units)
    except ValueError:
        return f"invalid units {units!r} (UDUNITS-2 cannot parse it)"
    return f"units {units!r} is unknown or no unit" if unit.is_unknown() or unit.is_no_unit() else None


def _variable_problems(name: str, var, listed: set[str]) -> list[str]:
    problems = []
    if var.dtype is str or isinstance(var.datatype, netCDF4.VLType):
        problems.append("ERROR (2.2): a variable-length string (vlen) variable, not a char array")
    if "long_name" not in var.ncattrs() and "standard_name" not in var.ncattrs():
        problems.append("WARN: neither long_name nor standard_name")
    if "standard_name" in var.ncattrs():
        problems.append("ERROR (3.3): a standard_name, which the empty table of cfchecks does not know")
    if "units" in var.ncattrs() and (problem := _units_problem(var.getncattr("units"))):
        problems.append(f"ERROR (3.1): {problem}")
    elif "units" not in var.ncattrs() and var.dtype != "S1":
        problems.append("WARN (project): no units attribute (roughcontact.pipeline.io writes units on every variable)")
    dims = var.dimensions
    if dims == (name,):  # a coordinate variable
        values = var[:]
        if np.asarray(values).dtype.kind not in "iuf":
            problems.append("ERROR (5): a coordinate variable that is not numeric (cfchecker 4.1 crashes on it)")
        elif np.ma.is_masked(values) or np.isnan(np.asarray(values, dtype=float)).any():
            problems.append("ERROR (5): coordinate variable with missing values")
        elif values.size > 1 and not (np.all(np.diff(values) > 0) or np.all(np.diff(values) < 0)):
            problems.append("ERROR (5): coordinate variable not monotonic")
    elif name in dims and name not in listed:
        problems.append("WARN (5): possible incorrect declaration of a coordinate variable "
                        "(a variable named after its dimension, not 1-D, listed in no `coordinates`)")
    return problems


def own_checks(path) -> list[str]:
    """The problems cfchecks would report that these checks see, as ``"name: ERROR (section): what"`` lines.

    Per variable: no vlen strings (CF 2.2); ``units`` that UDUNITS-2 parses to a unit (3.1);
    a ``long_name`` (or ``standard_name``, 3.3); coordinate variables numeric, strictly monotonic
    and without missing values (5); a variable named after one of its dimensions but not 1-D
    (a string label) listed in a ``coordinates`` attribute (5, 6.1), whose names all exist and
    whose label variables lead with one of the listing variable's dimensions; global
    ``Conventions`` ``CF-*``.
    """
    problems = []
    with netCDF4.Dataset(path) as nc:
        nc.set_auto_mask(True)
        if not str(getattr(nc, "Conventions", "")).startswith("CF-"):
            problems.append(f"global: ERROR (2.6.1): Conventions is {getattr(nc, 'Conventions', None)!r}")
        listed = set()
        for name, var in nc.variables.items():
            for coord in str(getattr(var, "coordinates", "")).split():
                listed.add(coord)
                if coord not in nc.variables:
                    problems.append(f"{name}: ERROR (5): coordinates names {coord!r}, which is not a variable")
                elif nc.variables[coord].dtype == "S1" and nc.variables[coord].dimensions[0] not in var.dimensions:
                    problems.append(f"{name}: ERROR (6.1): label {coord!r} does not lead with one of its dimensions")
        for name, var in nc.variables.items():
            problems += [f"{name}: {p}" for p in _variable_problems(name, var, listed)]
    return problems


def cf_problems(paths, tables_dir: Path) -> dict[Path, list[str]]:
    """ERROR and WARN lines per file: from ``cfchecks`` where it runs, else from :func:`own_checks`."""
    if cfchecks_command() is not None:
        return run_cfchecks(paths, tables_dir)
    return {Path(p): own_checks(p) for p in paths}


def assert_cf_clean(paths, tables_dir: Path) -> None:
    """Every one of ``paths`` has no CF error and no warning (by cfchecks, or by :func:`own_checks`), and
    :func:`own_checks` finds nothing either."""
    paths = [Path(p) for p in paths]
    assert paths
    found = cf_problems(paths, tables_dir)
    report = {p: lines for p in paths if (lines := found[p] + (own_checks(p) if cfchecks_command() else []))}
    assert not report, "\n".join(f"{p}:\n  " + "\n  ".join(lines) for p, lines in report.items())

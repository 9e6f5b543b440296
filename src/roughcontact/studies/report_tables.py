"""The report's tables of a scene's cases: the measured topographies as read and loaded, and an adhesive
scene's pull-off per group of cases (reStructuredText, for :mod:`roughcontact.studies.report`).

Their numbers are printed by :mod:`roughcontact.core.precision` (a mean with its standard deviation rounded
to it, a number without one to three figures) and their symbols as maths (``:math:``)."""

from __future__ import annotations

import itertools
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..core import precision
from ..core.cell import sides_of
from .rst import list_table, literal

#: Columns of :func:`topographies_table`, and what each row of it must give.
TOPOGRAPHY_COLUMNS = ("name", "file", "points", "size", "rms slope :math:`h'`", "undefined",
                      "final :math:`p_0/(E^* h')`", "final :math:`A/A_0`", "converged steps")


def topography_row(name: str, surface, contact=None) -> list[str]:
    """One measured case as a row of :func:`topographies_table`, as RST text.

    ``surface``: its surface dataset (``heights``, ``rms_slope``, ``undefined_fraction``, the cell's
    attributes and ``source``); ``contact``: its slice of the contact aggregate (``pressure``,
    ``area_fraction``, ``converged`` over ``step``, attribute ``e_star``) or None without a contact study.
    """
    source = json.loads(surface.attrs.get("source", "{}"))
    unit = surface.attrs.get("length_units", "1")
    if "y" in surface.sizes:
        nx, ny = (int(surface.sizes[d]) for d in ("x", "y"))
        lx, ly = sides_of(surface.attrs)
        points, size = f"{nx} x {ny}", f"{lx:.4g} x {ly:.4g} {unit}"
    else:  # a line scan: n points on its length L (resampled where the scan was not uniform)
        resampled = " (resampled)" if "resampled" in source else ""
        points, size = f"{int(surface.sizes['x'])}{resampled}", f"{float(surface.attrs['length']):.4g} {unit}"
    # a case's file holds its name as a length-1 dimension: its scalars have that one element
    slope = float(surface["rms_slope"].squeeze())
    undefined = float(surface["undefined_fraction"].squeeze()) if "undefined_fraction" in surface else 0.0
    row = [f"``{name}``", literal(Path(source.get("file", "?")).name), points, size, precision.bare(slope),
           f"{100 * undefined:.1f} %"]
    if contact is None:
        return row + ["", "", ""]
    p_last = float(contact["pressure"].isel(step=-1)) / (float(contact.attrs["e_star"]) * slope)
    conv = contact["converged"].values.astype(bool)
    return row + [precision.bare(p_last), precision.bare(float(contact["area_fraction"].isel(step=-1))),
                  f"{int(conv.sum())} of {conv.size}"]


def topographies_table(rows: Sequence[Sequence[str]]) -> str:
    """The measured cases of a scene (:func:`topography_row` each) as an RST table, with a lead-in."""
    return ("Each topography file, as read (size and unit after conversion, undefined points filled) and "
            "as loaded: the last load step's :math:`p_0/(E^* h')` and contact area fraction, and the load steps "
            "that converged.\n\n" + list_table(list(TOPOGRAPHY_COLUMNS), rows))


#: Columns of :func:`pull_off_table`: the pull-off is a mean pressure, its bar over p alone ("off" a subscript
#: beside it: :func:`roughcontact.studies.report.render_maths_as_mathml`).
PULL_OFF_COLUMNS = ("case", r"pull-off :math:`\bar p_\mathrm{off}/E^*` (mean ± s.d.)", "trusted", "left out (why)",
                    "process zone [cells]", "final :math:`A/A_0`")


def pull_off_table(agg) -> str:
    """An adhesive scene's pull-off per group of cases, as RST, with a lead-in saying what it is.

    ``agg`` is the contact aggregate (``pull_off_pressure``, ``pull_off_status``,
    ``adhesive_zone_cells``, ``area_fraction``, attribute ``e_star``), over ``(k_l, k_s, H, seed)``
    or ``topography``. A row per ``(k_l, k_s, H)`` (the seeds pooled: mean ± sample standard
    deviation of the trusted pull-offs, rounded to the deviation by :func:`~.precision.plus_minus`;
    a single trusted pull-off, and the other numbers, to three figures by :func:`~.precision.bare`) or per
    topography; the cases whose pull-off is NaN are counted by their status.
    """
    e_star = float(agg.attrs["e_star"])
    meanings = agg["pull_off_status"].attrs["flag_meanings"].split()
    measured = "topography" in agg.dims
    groups = ["topography"] if measured else ["k_l", "k_s", "H"]
    rows = []
    for key, part in _groups(agg, groups):
        present = (part["case_present"].values.astype(bool).ravel() if "case_present" in part
                   else np.ones(part["pull_off_status"].size, dtype=bool))
        pull = _flat(part["pull_off_pressure"])[present] / e_star
        codes = _flat(part["pull_off_status"])[present].astype(int)
        if codes.size == 0:
            continue
        ok = np.isfinite(pull)
        trusted = pull[ok]
        value = precision.MISSING if not ok.any() else (
            precision.plus_minus(trusted.mean(), trusted.std(ddof=1)) if ok.sum() > 1 else precision.bare(trusted[0]))
        why = ", ".join(f"{int((codes == c).sum())} {meanings[c].replace('_', ' ')}" for c in sorted(set(codes[~ok])))
        zone = _flat(part["adhesive_zone_cells"])[present]
        area = _flat(part["area_fraction"].isel(step=-1))[present]
        rows.append([key, value, f"{int(ok.sum())} of {codes.size}", why or "—", precision.bare(zone.min()),
                     precision.bare(np.nanmean(area))])
    lead = ("The pull-off pressure: minus the most tensile mean pressure on unloading under displacement control "
            "from the last load step, the step refined near the minimum until it moves by less than its tolerance. "
            r"It is trusted only where the grid resolves the adhesive process zone :math:`E^* \rho^2 / w` "
            r"(:math:`\rho` the range of the interaction, :math:`w` the work of adhesion; at least 1.5 cells), the "
            "last load step converged, the surfaces separated, the steps beside the minimum converged and the "
            "attraction dies out inside the cell (else its periodic images pull too); other cases are left out, "
            "counted by reason, and none of their unloading steps is flagged converged. No contact evolution law "
            "is fitted to an adhesive scene: the law and its theories describe contact without adhesion.\n\n")
    return lead + list_table(list(PULL_OFF_COLUMNS), rows)


def _flat(da) -> np.ndarray:
    """A variable's values as a flat float64 array."""
    return np.asarray(da.values, dtype=float).ravel()


def _groups(agg, dims: Sequence[str]):
    """``(label, part)`` for each combination of ``dims``' values (seeds stay in ``part``); the label is RST: a
    topography's name as a literal, a generated group's coordinates as maths (``k_l = 4``)."""
    axes = [agg[d].values for d in dims]
    for values in itertools.product(*axes):
        part = agg.sel(dict(zip(dims, values, strict=True)))
        if len(dims) == 1:
            yield f"``{values[0]}``", part
        else:
            # the dimensions' names are their symbols' TeX: k_l, k_s, H
            yield ", ".join(f":math:`{d} = {v:g}`" for d, v in zip(dims, values, strict=True)), part

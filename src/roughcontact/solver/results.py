"""Assembly of results: per-step records and the labelled ``xarray.Dataset``.

The solver's iterations work in internal units on flat arrays; this module is
the only place that knows the output's variable names, units and long names.
Units are per call: pressures carry the caller's ``pressure_unit`` (that of
``e_star``), lengths its ``length_unit`` (that of ``heights`` and ``length``), as CF
strings from :func:`roughcontact.core.quantities.cf_unit` (``"1"``: nondimensional).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..core.cell import Cell, sides_of
from ..core.quantities import cf_unit
from ..statistics.patches import patch_variables
from .workspace import SOLVER_PATHS

#: ``units`` attribute of dimensionless fractions, counts and flags.
FRACTION_UNITS = "1"

#: ``solver`` attribute of a pressure-iteration solve's output (a fixed provenance name, kept as
#: written by every earlier version; the adhesive solve writes its own, ``adhesion.solver``).
SOLVER_NAME = "roughcontact.solver.pk_pressure"
#: ``solver_description`` attribute of a pressure-iteration solve's output (periodic half-space).
SOLVER_DESCRIPTION = (
    "Pressure-controlled constrained conjugate gradient (Polonsky & Keer 1999) on a "
    "periodic FFT-BEM elastic half-space, u(q) = 2 p(q) / (E* |q|), Fourier-preconditioned "
    "(|q| E*/2 on the contact set) with an extrapolated warm start and float32 transforms inside "
    "the loop by default (attribute elastic_method; 'pk' is the plain iteration); with a hardness, "
    "monotone gradient-projection/CG on {0 <= p <= H, mean p = p0}; converged when "
    "max(sum_F(p|g|)/(sum(p) s), max(0,-min g below cap)/s, max(0,max g at cap)/s) <= tol "
    "with s the rms height, mean(p) = p0 to 1e-10 and 0 <= p (<= H), checked on a freshly "
    "recomputed displacement"
)
#: ``solver_description`` attribute for ``boundary="free"``.
SOLVER_DESCRIPTION_FREE = SOLVER_DESCRIPTION.replace(
    "periodic FFT-BEM elastic half-space, u(q) = 2 p(q) / (E* |q|)",
    "free-boundary FFT-BEM elastic half-space (pressure zero-padded to 2n x 2n and convolved with Love's "
    "influence function of a uniformly loaded square pixel, Hockney's method; no periodic images)",
).replace("(|q| E*/2 on the contact set)", "(periodic |q| E*/2 on the contact set, an approximate inverse)")


#: What a profile's ``solver_description`` says first (:func:`solver_description`).
PROFILE_DESCRIPTION = ("profile (1-D heights, plane strain: the surface is the same along y; u(q) = 2 p(q) / "
                       "(E* |q|) with q along x; the free half-space convolves with the plane-strain strip "
                       "2/(pi E*) ln(L/|x - s|) instead of Love's pixel, padded to 2n); ")


def solver_description(periodic: bool, square: bool = True, line: bool = False) -> str:
    """The ``solver_description`` attribute for the half-space and the cell (square, rectangular or a line)."""
    if line:
        return PROFILE_DESCRIPTION + solver_description(periodic)
    if periodic:
        return SOLVER_DESCRIPTION
    if square:
        return SOLVER_DESCRIPTION_FREE
    return SOLVER_DESCRIPTION_FREE.replace("2n x 2n", "2nx x 2ny").replace("square pixel", "rectangular pixel")


def periodic_elastic_attrs(settings, shape, fft_backend: str) -> dict:
    """The global attributes of a periodic elastic solve of ``shape`` (``(nx, ny)``) with ``settings``.

    As :func:`~.solve.solve_contact` writes them for the periodic half-space: modulus, the cell's
    sides and grid (:meth:`roughcontact.core.cell.Cell.solver_attrs`), tolerance, iterations, threads,
    ``fft_backend``, the solver's name and description; the batched and the MPI solvers' datasets
    start from these.
    """
    cell = Cell.of(shape, settings.length)
    sides, grid = cell.solver_attrs()
    return {"e_star": settings.e_star, **sides, "tol": settings.tol, "max_iter": settings.max_iter,
            "threads": settings.threads, "fft_backend": fft_backend, **grid, "solver": SOLVER_NAME,
            "solver_description": solver_description(True, cell.square)}


@dataclass
class StepResult:
    """Outcome of one load step of :func:`solve_step`.

    Attributes
    ----------
    p0 : float
        Applied mean pressure [pressure].
    pressure : numpy.ndarray, shape (nx, ny)
        Nodal contact pressure ``0 <= p (<= hardness)`` [pressure].
    gap : numpy.ndarray, shape (nx, ny)
        Gap ``g = u - h + d`` [length]; zero (to ``tol``) on the elastic contact set.
    area_fraction : float
        Fraction of nodes with ``p > 0`` [-].
    mean_gap : float
        Mean of ``gap`` over the cell [length].
    contact_perimeter : float
        Contact-set boundary length per unit nominal area [1/length].
    iterations : int
        Iterations (CG or gradient-projection steps).
    residual : float
        Residual of the final check (module docstring) [-].
    converged : bool
        The final check on a freshly recomputed displacement passed.
    wall_time : float
        Wall-clock seconds spent in the step.
    plastic_area_fraction, plastic_load_fraction : float or None
        Fraction of nodes at the hardness cap and share of the load they carry;
        ``None`` when no hardness is given.
    """

    p0: float
    pressure: np.ndarray
    gap: np.ndarray
    area_fraction: float
    mean_gap: float
    contact_perimeter: float
    iterations: int
    residual: float
    converged: bool
    wall_time: float
    plastic_area_fraction: float | None = None
    plastic_load_fraction: float | None = None




@dataclass
class StepRecord:
    """Physical outputs of one solved load step (internal to the solver)."""

    pressure: np.ndarray
    mask: np.ndarray
    area: float
    mean_gap: float
    perimeter: float
    iterations: int
    residual: float
    converged: bool
    effect_columns: dict
    path: str  # the iteration that ended the step: one of workspace.SOLVER_PATHS


def contact_perimeter(mask: np.ndarray, length=1.0, periodic: bool = True) -> float:
    """Length of the contact-set boundary per unit nominal area [1/length].

    Counts pixel edges between a contact and a non-contact node, each edge with its
    length: an edge between two nodes along x (neighbours along axis 0) is ``dy = Ly / ny``
    long, one between nodes along y is ``dx = Lx / nx`` long; the sum is divided by the
    cell's area ``Lx * Ly``. With periodic wrap in both directions (``periodic=True``, the
    periodic cell), or without it (``periodic=False``, a free patch), where nothing touches
    outside the patch, so that the outer edge of a contact node on the patch's border
    counts too.

    A profile (``mask`` of shape ``(n,)`` or ``(n, 1)``, a float ``length``) counts the ends of its
    contact intervals per unit length instead (:meth:`~roughcontact.core.cell.Cell.perimeter_per_area`).

    Parameters
    ----------
    mask : numpy.ndarray of bool, shape (nx, ny), or (n,) for a profile
        Contact set; square ``(n, n)`` when ``length`` is a float.
    length : float or (float, float)
        Side ``L`` of a square cell, or its sides ``(Lx, Ly)`` [length].
    periodic : bool
        Whether the cell wraps around (the solver's ``boundary="periodic"``).
    """
    m = np.asarray(mask, dtype=bool)
    m = m[:, None] if m.ndim == 1 else m
    edges_x, edges_y = _boundary_edges(m, periodic)
    # (L, L) on an n x n grid is the square cell L, as in the solver; the counts are exact in float64
    return Cell.canonical(m.shape, length, "mask").perimeter_per_area(float(edges_x), float(edges_y))


def _boundary_edges(m: np.ndarray, periodic: bool) -> tuple[int, int]:
    """Edges between contact and non-contact nodes: ``(along x, along y)`` (neighbours on axis 0, axis 1)."""
    if periodic:
        return (np.count_nonzero(m != np.roll(m, 1, axis=0)), np.count_nonzero(m != np.roll(m, 1, axis=1)))
    padded = np.pad(m, ((1, 1), (1, 1) if m.shape[1] > 1 else (0, 0)))  # no contact outside the patch
    return (np.count_nonzero(padded[1:, :] != padded[:-1, :]), np.count_nonzero(padded[:, 1:] != padded[:, :-1]))


def solver_path_variable(codes, names=SOLVER_PATHS) -> xr.Variable:
    """The per-step ``solver_path`` variable: a CF flag (``flag_values``, ``flag_meanings``) over ``step``.

    ``codes`` (int8, shape (n_steps,)) index ``names``, the iterations the solver can end a step
    on (:data:`~.workspace.SOLVER_PATHS` for the pressure iterations); a code other than the
    scene's method says that the step stalled on it and a fallback ended it.
    """
    codes = np.asarray(codes, dtype=np.int8)
    return xr.Variable(("step",), codes, {
        "units": FRACTION_UNITS, "long_name": "iteration that ended the load step (after a stall, a fallback)",
        "flag_values": np.arange(len(names), dtype=np.int8),
        "flag_meanings": " ".join(name.replace("-", "_") for name in names)})


def path_names(ds: xr.Dataset) -> tuple[str, ...]:
    """The iterations ``ds["solver_path"]`` codes index, read back from its ``flag_meanings``."""
    return tuple(name.replace("_", "-") for name in ds["solver_path"].attrs["flag_meanings"].split())


def to_dataset(p, cols, iters, conv, fields, store_fields, shape, attrs: dict, effects=(), *, paths=None,
               length_unit: str = "1", pressure_unit: str = "1", path_names=SOLVER_PATHS,
               long_names: dict | None = None) -> xr.Dataset:
    """The solver's output dataset (see :func:`roughcontact.solver.solve_contact`).

    ``shape`` the grid ``(nx, ny)`` (an int ``n``: ``(n, n)``), the cell's sides being in
    ``attrs`` (:meth:`roughcontact.core.cell.Cell.solver_attrs`): the stored fields' ``x`` and ``y`` coordinates step by
    ``dx = Lx / nx`` and ``dy = Ly / ny``. ``p`` the loads, shape (n_steps,); ``cols``
    per-step float columns by name (including each effect's) and the int columns ``contact_nodes`` and
    ``largest_patch_nodes`` (:func:`roughcontact.statistics.patches.contact_patches`); ``iters``, ``conv``
    per-step iterations and flags; ``fields`` a ``(pressures, gaps, step numbers)`` triple of the
    stored fields; ``attrs`` the solver's global attributes; ``effects`` add
    their variables and attributes; ``paths`` the per-step codes into
    :data:`~.workspace.SOLVER_PATHS` (int8, shape (n_steps,)) of the iteration that ended each step
    (:func:`solver_path_variable`). ``length_unit`` and ``pressure_unit`` (one of
    :data:`roughcontact.core.quantities.LENGTH_UNITS` / ``PRESSURE_UNITS``) give the
    ``units`` of lengths, pressures and ``contact_perimeter`` [length^-1], and the
    global attributes ``length_units`` and ``pressure_units``. ``path_names`` are the
    iterations ``paths`` index; ``long_names`` replace the default long names of the per-step
    variables where the solver defines them otherwise (the adhesive solver's contact area).
    """
    pressure_units = cf_unit(pressure=pressure_unit, pressure_power=1)
    length_units = cf_unit(length_unit, length_power=1)
    meta = _step_meta(p, cols, iters, conv, pressure_units, length_units, cf_unit(length_unit, length_power=-1))
    for name, long_name in (long_names or {}).items():
        meta[name] = (*meta[name][:2], long_name)
    for effect in effects:
        for name, (units, long_name) in effect.variables(length_unit=length_unit,
                                                         pressure_unit=pressure_unit).items():
            meta[name] = (cols[name], units, long_name)
    data_vars = {name: xr.Variable(("step",), val, {"units": u, "long_name": ln})
                 for name, (val, u, ln) in meta.items()}
    if paths is not None:
        data_vars["solver_path"] = solver_path_variable(paths, path_names)
    coords = {"step": xr.Variable(("step",), np.arange(1, p.size + 1),
                                  {"units": FRACTION_UNITS, "long_name": "load step number (1-based)"})}
    if fields[2]:
        _add_fields(data_vars, coords, fields, store_fields, shape, attrs, pressure_units, length_units)
    attrs = {**attrs, "length_units": length_units, "pressure_units": pressure_units}
    for effect in effects:
        attrs.update(effect.attrs())
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def _step_meta(p, cols, iters, conv, pressure_units, length_units, inverse_length_units) -> dict:
    """The solver's per-step variables: name -> (values (n_steps,), CF units, long name)."""
    return {
        "pressure": (p, pressure_units, "applied mean pressure p0 = F / A0"),
        "area_fraction": (cols["area_fraction"], FRACTION_UNITS,
                          "real contact area fraction A / A0 (fraction of nodes with p > 0)"),
        "mean_contact_pressure": (cols["mean_contact_pressure"], pressure_units,
                                  "mean contact pressure F / A = p0 / (A / A0)"),
        "mean_gap": (cols["mean_gap"], length_units,
                     "mean gap between the rigid surface and the deformed half-space"),
        "contact_perimeter": (cols["contact_perimeter"], inverse_length_units,
                              # one text for every cell, so that square and rectangular cases aggregate
                              "contact-set boundary length (pixel edges, dy long between neighbours along x and dx "
                              "along y) per unit nominal area"),
        "iterations": (iters, FRACTION_UNITS, "solver iterations (CG or gradient-projection steps)"),
        "residual": (cols["residual"], FRACTION_UNITS,
                     "final scale-free residual max(sum_F(p|g|)/(sum(p) s), max(0,-min g below cap)/s, "
                     "max(0,max g at cap)/s) on a freshly recomputed displacement"),
        "converged": (conv, FRACTION_UNITS,
                      "residual <= tol, mean(p) = p0 to 1e-10 and 0 <= p (<= hardness) on a freshly "
                      "recomputed displacement"),
        "wall_time": (cols["wall_time"], "s", "wall-clock time of the load step"),
        **patch_variables(cols["contact_nodes"], cols["largest_patch_nodes"]),
    }


def _add_fields(data_vars: dict, coords: dict, fields, store_fields, shape, attrs: dict, pressure_units: str,
                length_units: str) -> None:
    """Add the stored pressure and gap fields (dims ``step`` or ``field_step``, ``x``, ``y``; a profile's
    ``step`` or ``field_step``, ``x``) in place."""
    fields_p, fields_g, field_steps = fields
    dim = "step" if (isinstance(store_fields, (bool, np.bool_)) and store_fields) else "field_step"
    xs, ys = _node_positions(shape, attrs)
    coords["x"] = xr.Variable(("x",), xs, {"units": length_units, "long_name": "node position along axis 0"})
    if int(attrs.get("surface_dimension", 2)) == 1:
        dims = (dim, "x")
        fields_p, fields_g = [f.reshape(-1) for f in fields_p], [f.reshape(-1) for f in fields_g]
    else:
        dims = (dim, "x", "y")
        coords["y"] = xr.Variable(("y",), ys, {"units": length_units, "long_name": "node position along axis 1"})
    if dim == "field_step":
        coords["field_step"] = xr.Variable(("field_step",), np.array(field_steps),
                                           {"units": FRACTION_UNITS,
                                            "long_name": "load step number of the stored fields"})
    data_vars["contact_pressure"] = xr.Variable(
        dims, np.stack(fields_p), {"units": pressure_units, "long_name": "nodal contact pressure"})
    data_vars["gap"] = xr.Variable(
        dims, np.stack(fields_g), {"units": length_units,
                                   "long_name": "gap between the rigid surface and the half-space"})


def _node_positions(shape, attrs: dict) -> tuple[np.ndarray, np.ndarray]:
    """Node positions ``i dx`` along x and ``j dy`` along y [length], shapes (nx,) and (ny,)."""
    nx, ny = (shape, shape) if np.ndim(shape) == 0 else shape
    lx, ly = sides_of(attrs)
    xs = np.arange(nx) * (lx / nx)
    if int(attrs.get("surface_dimension", 2)) == 1:
        return xs, np.zeros(1)
    if "length_x" not in attrs:  # square cell: the same positions along y
        return xs, xs.copy()
    return xs, np.arange(ny) * (ly / ny)


def step_notes(ds: xr.Dataset) -> list[str]:
    """One line per load step of :func:`~roughcontact.solver.solve_contact`'s ``ds`` that was not plain.

    A step ended by a fallback says which iteration converged it (the scene's own stalled on that
    step, or on an earlier one, after which the steps start on the fallback); an unconverged step
    says why: ``max_iter`` reached (cap) or every iteration stalled (stall), with its residual. Steps
    solved by the scene's own iteration (the capped ``box`` iteration when there is a hardness),
    converged, give no line.
    """
    method, max_iter = ds.attrs.get("elastic_method"), int(ds.attrs["max_iter"])
    plain = {method, "exact"} | ({"box"} if "hardness" in ds.attrs else set())
    notes = []
    for k, step in enumerate(ds["step"].values):
        path = path_names(ds)[int(ds["solver_path"].values[k])] if "solver_path" in ds else method
        its, residual = int(ds["iterations"].values[k]), float(ds["residual"].values[k])
        if not bool(ds["converged"].values[k]):
            why = f"max_iter = {max_iter} reached" if its >= max_iter else f"stalled, last on {path}"
            notes.append(f"step {step}: NOT converged ({why}; residual {residual:.3g} after {its} iterations)")
        elif path not in plain:
            notes.append(f"step {step}: converged by the fallback {path} ({its} iterations in all; {method} "
                         "stalled on this step or an earlier one)")
    return notes

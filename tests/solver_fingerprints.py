"""Fingerprints of the solver's results, to show a refactoring changed no bit.

``python tests/solver_fingerprints.py OUT.json`` solves a fixed set of problems (every elastic
method, both boundaries, with and without a hardness cap, square and rectangular cells, flat
surfaces, warm starts across load steps, stored fields and clusters) and writes one SHA-256 per
problem over every output variable's bytes except ``wall_time`` (the only value that depends on
the machine's load), plus the global attributes. Run it on the code before and after a change
on one machine and compare the two files: equal fingerprints mean bit-identical results. Across
machines the floating-point results legitimately differ in the last bits
(tests/compare_outputs.py), so the files are not committed as references.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import sys

import numpy as np

from roughcontact import solver as solver_mod
from roughcontact.solver import solve_contact, solve_step
from roughcontact.statistics.clusters import ClusterObserver
from roughcontact.surfaces.synthetic import generate_surface

LOADS = [0.002 * k for k in range(1, 7)]


def digest(ds) -> str:
    """SHA-256 over every variable (name, dtype, bytes) but ``wall_time``, and the attributes."""
    h = hashlib.sha256()
    for name in sorted(ds.variables):
        if name == "wall_time":
            continue
        values = np.ascontiguousarray(ds[name].values)
        h.update(f"{name}:{values.dtype}:{values.shape}".encode())
        h.update(values.tobytes() if values.dtype != object else repr(values.tolist()).encode())
    h.update(json.dumps({k: str(v) for k, v in sorted(ds.attrs.items())}).encode())
    return h.hexdigest()


def problems():
    """``(name, thunk)`` for every fingerprinted problem."""
    sq = generate_surface(64, 2, 16, 0.5, seed=3, rms_slope=0.1)
    rect = generate_surface(64, 2, 16, 0.5, seed=4, rms_slope=0.1)[:, :40]
    flat = np.zeros((32, 32))
    cases = []
    for method, boundary, hardness in itertools.product(("pk", "pk-fourier", "pk-fourier-f32"),
                                                        ("periodic", "free"), (None, 0.02)):
        for shape_name, h, length in (("square", sq, 1.0), ("rect", rect, (1.0, 40 / 64))):
            name = f"{method}/{boundary}/H={hardness}/{shape_name}"
            cases.append((name, method, dict(heights=h, pressures=LOADS, length=length, boundary=boundary,
                                             hardness=hardness, store_fields=[2, 6],
                                             observers=[ClusterObserver(length, boundary == "periodic")])))
    cases.append(("flat/periodic", "pk-fourier-f32", dict(heights=flat, pressures=LOADS[:3])))
    cases.append(("flat/free", "pk-fourier-f32", dict(heights=flat, pressures=LOADS[:3], boundary="free")))
    cases.append(("tol-1e-12", "pk-fourier-f32", dict(heights=sq, pressures=LOADS, tol=1e-12)))
    cases.append(("units", "pk-fourier-f32", dict(heights=sq * 1e-6, pressures=[1e3, 5e3], e_star=2e9,
                                                   length=3e-3, length_unit="m", pressure_unit="Pa")))
    return cases


def fingerprints() -> dict[str, str]:
    out = {}
    for name, method, kwargs in problems():
        with solver_mod.set_options(method=method):
            out[name] = digest(solve_contact(kwargs.pop("heights"), kwargs.pop("pressures"), **kwargs))
    sq = generate_surface(64, 2, 16, 0.5, seed=3, rms_slope=0.1)
    for hardness in (None, 0.02):
        st = solve_step(sq, 0.004, hardness=hardness, initial_pressure=np.abs(sq))
        h = hashlib.sha256(st.pressure.tobytes() + st.gap.tobytes())
        h.update(repr((st.area_fraction, st.mean_gap, st.contact_perimeter, st.iterations, st.residual,
                       st.converged, st.plastic_area_fraction, st.plastic_load_fraction)).encode())
        out[f"step/H={hardness}"] = h.hexdigest()
    return out


if __name__ == "__main__":
    result = fingerprints()
    with open(sys.argv[1], "w") as f:
        json.dump(result, f, indent=1, sort_keys=True)
    print(f"{len(result)} fingerprints -> {sys.argv[1]}")

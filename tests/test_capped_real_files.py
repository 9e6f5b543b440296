"""The capped iteration on real instrument files, from the starts that once stalled it.

Both files are SurfaceTopography's examples (tests/data/surfacetopography, MIT), read as a measured
scene reads them and loaded as ``benchmarks/formats/sweep.py --solve --hardness 0.2`` does: steps
to p0/(E* h') = 0.05 in 30, a cap of 0.2 E* h', free boundary. The last step of each case ran into
the stall window (300 iterations) with nearly every node still in contact: nid-1's first step (a
cold start from the uniform pressure), spot_1's third (its scaled last solution could not carry
the load at the cap, and the rest went to every node). From such a start each CG step left the box,
moved only part of the way to its projection and released a node or two. Now a move that stops
short is followed by a gradient-projection step (``BoxIteration.expand``), which releases them by
the thousand. Checked: every step converges well inside the window and satisfies every invariant of
:func:`solver_invariants.check_solution`.
"""
from pathlib import Path

import pytest

from roughcontact.solver import solve_contact
from roughcontact.surfaces.synthetic import nonperiodic_moments
from roughcontact.surfaces.topography import read_topography
from solver_invariants import check_solution

DATA = Path(__file__).resolve().parent / "data" / "surfacetopography"

#: A step of these cases takes 16-22 iterations (measured); the stall window is 300.
MAX_STEP_ITERATIONS = 100


@pytest.mark.parametrize("name, steps", [("nid-1.nid", 1), ("spot_1-1000nm.ibw", 3)])
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_capped_steps_of_real_files_converge(name, steps):
    s = read_topography(DATA / name, unit="um", undefined="harmonic", detrend="height")
    slope = nonperiodic_moments(s.heights, s.lengths)["rms_slope"]
    loads = [0.05 * slope * (k + 1) / 30 for k in range(steps)]
    hardness = 0.2 * slope
    ds = solve_contact(s.heights, loads, e_star=1.0, length=s.length, tol=1e-8, boundary="free",
                       hardness=hardness, store_fields=True)
    assert ds["converged"].values.all(), ds["iterations"].values
    assert ds["iterations"].values.max() <= MAX_STEP_ITERATIONS, ds["iterations"].values
    # a few per cent of the nodes in contact, a good part of them at the cap: not the uniform start
    assert 0.005 < float(ds["area_fraction"][-1]) < 0.05
    assert 0.2 < float(ds["plastic_area_fraction"][-1] / ds["area_fraction"][-1]) < 1
    check_solution(ds, s.heights, tol=1e-8, length=s.length, hardness=hardness, boundary="free")

"""Contact patches of a load step (statistics.patches): node counts, the largest patch, the resolution rule,
the slab merge of the MPI solver, and the per-step variables every solver writes."""
import functools
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from roughcontact.solver import solve_contact
from roughcontact.statistics.clusters import cluster_statistics
from roughcontact.statistics.patches import (
    MIN_PATCH_NODES,
    contact_patches,
    merge_slabs,
    patch_sizes,
    resolved,
    resolved_variable,
    slab_patches,
)

B = bool


def runs(bits: str) -> np.ndarray:
    """A profile's mask from a string of 0 and 1."""
    return np.array([c == "1" for c in bits], dtype=B)


# ------------------------------------------------------------------------------------------ profiles
@pytest.mark.parametrize("bits, periodic, sizes", [
    ("0110100111", True, [3, 2, 1]),     # node 9 is in contact, node 0 is not: no run wraps
    ("1100100111", True, [5, 1]),        # the runs at both ends are one across the period
    ("1100100111", False, [3, 2, 1]),    # a free profile: its ends do not touch
    ("1111111111", True, [10]),
    ("1111111111", False, [10]),
    ("0000000000", True, []),
    ("1010101010", True, [1, 1, 1, 1, 1]),
])
def test_runs_of_a_profile(bits, periodic, sizes):
    m = runs(bits)
    assert patch_sizes(m, periodic).tolist() == sizes
    assert patch_sizes(m[:, None], periodic).tolist() == sizes  # the solver's (n, 1) grid of a profile
    assert contact_patches(m, periodic) == (int(m.sum()), sizes[0] if sizes else 0)


# ------------------------------------------------------------------------------------------ maps
def test_a_map_patch_joins_across_both_edges_only_when_periodic():
    m = np.zeros((6, 5), B)
    m[0, 0] = m[-1, 0] = m[0, -1] = True     # three corners, neighbours around the torus
    m[3, 2] = True
    assert patch_sizes(m, True).tolist() == [3, 1]
    assert patch_sizes(m, False).tolist() == [1, 1, 1, 1]


def test_corner_neighbours_are_separate_patches():
    m = np.eye(5, dtype=B)
    assert patch_sizes(m, False).tolist() == [1] * 5


@pytest.mark.parametrize("periodic", [True, False])
@pytest.mark.parametrize("shape", [(16, 16), (12, 7), (9, 1)])
def test_maps_agree_with_the_cluster_labels(periodic, shape):
    rng = np.random.default_rng(sum(shape))
    for fill in (0.1, 0.4, 0.6):
        m = rng.random(shape) < fill
        st = cluster_statistics(m, (1.0, shape[1] / shape[0]), periodic)
        assert patch_sizes(m, periodic).tolist() == st["areas_pixels"].tolist()


def test_a_bad_mask_is_refused():
    with pytest.raises(ValueError, match="dtype bool"):
        patch_sizes(np.ones(4))
    with pytest.raises(ValueError, match="profile"):
        patch_sizes(np.ones((2, 2, 2), B))


# ------------------------------------------------------------------------------------------ the rule
def test_the_threshold_is_four_nodes_in_the_largest_patch():
    assert MIN_PATCH_NODES == 4
    assert resolved([0, 1, 3, 4, 40]).tolist() == [False, False, False, True, True]
    assert resolved(np.array([[3, 4], [12, 2]])).tolist() == [[False, True], [True, False]]


def test_many_small_patches_are_unresolved_however_many_nodes_they_hold():
    m = runs("110" * 30)                   # 60 contact nodes, every patch 2 nodes
    nodes, largest = contact_patches(m, False)
    assert (nodes, largest) == (60, 2) and not resolved(largest)
    m[:5] = True                           # one patch of 5 beside them: resolved
    assert contact_patches(m, False)[1] == 5 and resolved(5)


def test_few_contact_nodes_in_all_are_unresolved():
    # the contact is held by two nodes: no patch can span four (the line scans' flat steps)
    assert contact_patches(runs("0" * 40 + "11" + "0" * 34), False) == (2, 2)
    assert not resolved(2)


def test_a_map_of_many_specks_is_unresolved_until_one_spot_holds_four_nodes():
    m = np.zeros((33, 33), B)
    m[::3, ::3] = True                     # 121 one-node specks
    m[0::6, 1::6] = True                   # 36 of them two nodes
    nodes, largest = contact_patches(m, True)
    assert (nodes, largest) == (157, 2) and not resolved(largest)
    m[10, 10:12] = True                    # one L of 3 nodes
    m[11, 10] = True
    assert contact_patches(m, True)[1] == 3 and not resolved(3)
    m[10:13, 13] = True                    # 2 x 2 beside the L: a spot of 4 nodes and more
    m[12, 12] = True
    assert contact_patches(m, True)[1] >= 4 and resolved(contact_patches(m, True)[1])


def test_the_flag_variable_is_a_cf_flag_that_states_its_rule():
    da = resolved_variable(xr.DataArray(np.array([2, 3, 4, 9]), dims=("step",)))
    assert da.dtype == bool and da.values.tolist() == [False, False, True, True]
    assert da.attrs["flag_values"].tolist() == [0, 1] and da.attrs["flag_meanings"] == "unresolved resolved"
    assert da.attrs["units"] == "1" and "at least 4 nodes" in da.attrs["long_name"] and da.attrs["min_patch_nodes"] == 4


# ------------------------------------------------------------------------------------------ slabs
@pytest.mark.parametrize("periodic", [True, False])
@pytest.mark.parametrize("ranks", [1, 2, 3, 5])
def test_the_slab_merge_is_the_whole_grids_largest_patch(periodic, ranks):
    rng = np.random.default_rng(ranks)
    for fill in (0.05, 0.3, 0.55, 0.7, 1.0):
        m = rng.random((23, 11)) < fill
        m[:, 4] |= fill > 0.5              # a band along x through every slab
        cuts = np.linspace(0, m.shape[0], ranks + 1).astype(int)
        parts = [slab_patches(m[a:b], periodic) for a, b in zip(cuts[:-1], cuts[1:], strict=True)]
        assert merge_slabs(parts, periodic) == contact_patches(m, periodic), (fill, ranks)


def test_a_patch_across_every_slab_boundary_is_one_patch():
    m = np.zeros((12, 4), B)
    m[:, 1] = True                         # a line along x through three slabs, around the period
    parts = [slab_patches(m[a:a + 4]) for a in (0, 4, 8)]
    assert merge_slabs(parts, True) == (12, 12)
    assert merge_slabs([slab_patches(m[a:a + 4], False) for a in (0, 4, 8)], False) == (12, 12)


# ------------------------------------------------------------------------------------------ the solvers
def _masks(ds) -> np.ndarray:
    return ds.contact_pressure.values > 0


@pytest.mark.parametrize("boundary", ["periodic", "free"])
@pytest.mark.parametrize("dimension", [1, 2])
def test_every_step_of_a_solve_reports_its_patches(boundary, dimension):
    from roughcontact.surfaces.synthetic import generate_profile, generate_surface

    make = generate_profile if dimension == 1 else generate_surface
    h = make(256 if dimension == 1 else 32, 2, 16, 0.8, 1, rms_slope=0.1)
    ds = solve_contact(h, [0.0005, 0.002, 0.008], boundary=boundary, store_fields=True)
    for name in ("contact_nodes", "largest_patch_nodes"):
        assert ds[name].dtype == np.int64 and ds[name].dims == ("step",) and ds[name].attrs["units"] == "1"
    expected = [contact_patches(m, boundary == "periodic") for m in _masks(ds)]
    assert list(zip(ds.contact_nodes.values.tolist(), ds.largest_patch_nodes.values.tolist(), strict=True)) == expected
    np.testing.assert_array_equal(ds.contact_nodes.values, np.round(ds.area_fraction.values * h.size))


def test_a_batch_reports_each_cases_patches_as_its_single_solve():
    from roughcontact.solver.batch import solve_contact_batch
    from roughcontact.surfaces.synthetic import generate_surface

    hs = np.stack([generate_surface(32, 2, 16, 0.8, s, rms_slope=0.1) for s in range(2)])
    loads = [0.001, 0.004]
    batch = solve_contact_batch(hs, loads)
    for b in range(2):
        single = solve_contact(hs[b], loads, store_fields=True)
        expected = [contact_patches(m) for m in _masks(single)]
        got = list(zip(batch.contact_nodes.values[b].tolist(), batch.largest_patch_nodes.values[b].tolist(),
                       strict=True))
        assert got == expected


# ------------------------------------------------------------------------------------------ the contact file
LINESCANS = Path(__file__).parent / "data" / "linescans"


@functools.cache
def _line_scan_case(name: str = "xy-1.txt", steps: int = 30):
    """A real line scan (SurfaceTopography's non-uniform ``xy-1.txt``, 132 points) solved as a measured scene
    solves it (free boundary, plane strain, loads to p0/(E* h') = 0.05): its contact dataset."""
    from roughcontact.pipeline.datasets import contact_dataset
    from roughcontact.surfaces.synthetic import profile_moments
    from roughcontact.surfaces.topography import read_topography

    s = read_topography(LINESCANS / name, unit="um", file_unit="um", detrend="height")
    stats = profile_moments(s.heights, s.lengths[0])
    loads = 0.05 * stats["rms_slope"] * np.arange(1, steps + 1) / steps
    result = solve_contact(s.heights, loads, length=s.length, boundary="free", store_fields=True,
                           length_unit="um", pressure_unit="MPa")
    return contact_dataset(result, rms_slope=stats["rms_slope"], alpha=stats["alpha"], e_star=1.0,
                           topography=name.split(".")[0])


def test_a_real_line_scans_flat_steps_are_unresolved_in_its_contact_file():
    ds = _line_scan_case().squeeze("topography")
    flag, largest = ds.contact_resolved.values, ds.largest_patch_nodes.values
    a = ds.area_fraction.values
    # the first six steps: A/A0 flat at 3 of 132 nodes while the load rises six-fold, one patch of 3 nodes
    assert np.all(a[:6] == 3 / 132) and ds.contact_nodes.values[:6].tolist() == [3] * 6
    assert largest[:6].tolist() == [3] * 6 and not flag[:6].any()
    # from the seventh on a patch of 5 nodes or more: resolved
    assert largest[6] == 5 and flag[6:].all() and np.all(largest[6:] >= 4)
    assert flag.tolist() == resolved(largest).tolist()
    assert ds.contact_resolved.attrs["min_patch_nodes"] == 4 and ds.contact_resolved.attrs["flag_values"].tolist() \
        == [0, 1]


def test_the_contact_file_is_cf_clean_and_the_flag_survives_a_round_trip(tmp_path):
    from cfcheck import assert_cf_clean
    from roughcontact.pipeline.io import read_dataset, write_dataset

    ds = _line_scan_case().drop_vars(["contact_pressure", "gap"])
    path = write_dataset(ds, tmp_path / "xy.nc", stage="contact", scene="t", scene_parameters={})
    back = read_dataset(path, stage="contact")
    assert back.contact_resolved.dtype == bool
    assert back.contact_resolved.values.tolist() == ds.contact_resolved.values.tolist()
    assert_cf_clean([path], tmp_path / "cf")


def test_the_aggregate_counts_the_unresolved_steps_of_each_case():
    from roughcontact.analysis.aggregate import add_derived, combine_topographies

    parts = [_line_scan_case("xy-1.txt"), _line_scan_case("nonuniform.asc")]
    parts = [p.drop_vars(["contact_pressure", "gap", "x"]) for p in parts]
    agg = add_derived(combine_topographies(parts, ["xy", "nu"], expected=["xy-1", "nonuniform"]))
    assert agg.contact_resolved.dims == ("topography", "step") and agg.contact_resolved.dtype == bool
    assert agg.n_unresolved.sel(topography="xy-1").item() == 6
    # nonuniform.asc: patches of at most 3 nodes over its first 19 steps (A/A0 flat at 7 nodes over ten of them)
    assert agg.n_unresolved.sel(topography="nonuniform").item() == 19
    assert agg.n_unresolved.attrs["units"] == "1" and "unresolved" in agg.n_unresolved.attrs["long_name"]


def _line_scans_aggregate():
    from roughcontact.analysis.aggregate import add_derived, combine_topographies

    parts = [p.drop_vars(["contact_pressure", "gap", "x"]) for p in
             (_line_scan_case("xy-1.txt"), _line_scan_case("nonuniform.asc"))]
    return add_derived(combine_topographies(parts, ["xy", "nu"], expected=["xy-1", "nonuniform"]))


def test_the_fit_leaves_the_unresolved_steps_out_and_counts_them():
    from roughcontact.analysis.fit import fit_topographies, unresolved_in_window, usable_steps

    agg, window = _line_scans_aggregate(), (0.02, 0.3)
    a, flag = agg.area_fraction, agg.contact_resolved
    inside = (a >= window[0]) & (a <= window[1])
    n_out = unresolved_in_window(agg, window)
    assert n_out == int((inside & ~flag).sum()) > 0
    assert usable_steps(agg).values.tolist() == (agg.converged & flag).values.tolist()
    kw = dict(window=window, n_boot=10, min_points=3, methods=["paper"], paper_average="none")  # every point
    fitted = fit_topographies(agg, **kw)
    # exactly the fit of the same steps with the unresolved ones marked unconverged
    older = agg.drop_vars(["contact_resolved", "n_unresolved"])
    as_unconverged = fit_topographies(older.assign(converged=agg.converged & flag), **kw)
    xr.testing.assert_identical(fitted.value, as_unconverged.value)
    xr.testing.assert_identical(fitted.n_points, as_unconverged.n_points)
    # with the plateaus in (an older file's, without the flag), d pbar/d p0 = 1/(A/A0) on them bends the
    # log-log line past the CEL's range: mu > 1, no fit
    unflagged = fit_topographies(older, **kw)
    assert np.isfinite(fitted.value.sel(estimator="paper")).all() and unflagged.value.isnull().all()


# ------------------------------------------------------------------------------------------ the figures
def _marks(fig):
    from roughcontact.figures.unresolved import UNRESOLVED_GID

    return [line for ax in fig.axes for line in ax.get_lines() if line.get_gid() == UNRESOLVED_GID]


def _legend(fig):
    return [t.get_text() for leg in fig.legends for t in leg.get_texts() if "unresolved" in t.get_text()]


@pytest.mark.parametrize("name", ["measured_area_load", "measured_kappa"])
def test_the_measured_figures_mark_a_real_line_scans_unresolved_steps_and_say_so(name):
    """xy-1.txt's six flat steps (one patch of 3 nodes) and nonuniform.asc's nineteen (patches of 1 to 3 nodes)
    are circled, counted in the legend and named with their node counts in the caption; without the flag (a file
    of an older version) nothing is."""
    from caption_check import lead_of
    from roughcontact.figures.captions import caption
    from roughcontact.figures.measured import fig_measured_area_load, fig_measured_kappa
    from roughcontact.figures.record import figure_record

    draw = {"measured_area_load": fig_measured_area_load, "measured_kappa": fig_measured_kappa}[name]
    agg = _line_scans_aggregate()
    fig = draw(agg)
    (line,) = _marks(fig)
    bad = ~agg.contact_resolved
    assert len(line.get_xdata()) == int(bad.sum()) == 25
    assert sorted(line.patch_nodes.tolist()) == sorted(agg.largest_patch_nodes.values[bad.values].tolist())
    assert _legend(fig) == ["25 unresolved load steps: largest contact patch 1 to 3 nodes, under 4"]
    text = caption(lead_of(name), figure_record(name, fig))
    assert ("Hollow black circles: 25 load steps whose contact is unresolved: the grid does not resolve it, the "
            "largest contact patch holding 1 to 3 nodes, fewer than 4.") in text
    one = draw(agg.sel(topography=["xy-1"]))   # one scan: one patch of 3 nodes, six times
    assert ("6 load steps whose contact is unresolved: the grid does not resolve it, the largest contact patch "
            "holding 3 nodes") in caption(lead_of(name), figure_record(name, one))
    older = draw(agg.drop_vars(["contact_resolved", "n_unresolved"]))
    assert not _marks(older) and not _legend(older)
    assert "resolve" not in caption(lead_of(name), figure_record(name, older))


def _with_unresolved(agg, family=(16.0, 32.0, 0.84), seeds=(0, 1), steps=(1, 2, 3)):
    """A synthetic aggregate (no solver) with per-step patch variables: every step resolved (40 nodes in its
    largest patch) but ``steps`` of ``seeds`` of ``family``, whose largest patch holds 2 nodes."""
    from roughcontact.analysis.aggregate.derived import add_derived
    from roughcontact.statistics.patches import resolved_variable

    largest = xr.full_like(agg["area_fraction"], 40.0)
    largest.loc[dict(zip(("k_l", "k_s", "H"), family, strict=True), seed=list(seeds), step=list(steps))] = 2.0
    out = agg.drop_vars(["kappa", "dpbar_dp0", "n_unconverged"]).assign(largest_patch_nodes=largest)
    out["contact_resolved"] = resolved_variable(largest) | ~out["case_present"]
    return add_derived(out)


@pytest.mark.parametrize("name", ["area_load", "kappa"])
def test_the_generated_figures_mark_each_unresolved_case_step_in_its_panel(name):
    from caption_check import lead_of
    from cel_synthetic import simulate_cel_cases
    from roughcontact.analysis.aggregate import aggregate_contact, seed_statistics
    from roughcontact.figures.area_load import fig_area_load
    from roughcontact.figures.captions import caption
    from roughcontact.figures.kappa import fig_kappa
    from roughcontact.figures.record import figure_record

    dss, names = simulate_cel_cases(k_l=(4.0, 16.0), k_s=(32.0, 128.0), hurst=(0.36, 0.84), seeds=range(3),
                                    point_noise=1e-4, seed_scatter=0.01, rng_seed=5)
    plain = aggregate_contact(dss, names)
    agg = _with_unresolved(plain)
    draw = {"area_load": fig_area_load, "kappa": fig_kappa}[name]
    fig = draw(agg, seed_statistics(agg))
    (line,) = _marks(fig)
    assert line.axes is fig.axes[0]        # the k_s = 32 panel, not the k_s = 128 one
    case = agg.sel(k_l=16.0, k_s=32.0, H=0.84, seed=[0, 1], step=[1, 2, 3])
    y = case["area_fraction" if name == "area_load" else "kappa"].values.ravel()
    np.testing.assert_allclose(np.sort(line.get_ydata()), np.sort(y))
    assert _legend(fig) == ["6 unresolved load steps: largest contact patch 2 nodes, under 4"]
    assert ("6 load steps whose contact is unresolved: the grid does not resolve it, the largest contact patch "
            "holding 2 nodes, fewer than 4.") in caption(lead_of(name), figure_record(name, fig))
    for data in (_with_unresolved(plain, steps=()), plain):   # all resolved; no flag
        fig = draw(data, seed_statistics(data))
        assert not _marks(fig) and not _legend(fig)

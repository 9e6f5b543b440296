"""Combining per-case datasets, derived quantities and seed statistics."""

import numpy as np
import pytest
import xarray as xr

from cel_synthetic import simulate_cel_cases
from roughcontact.analysis.aggregate.combine import CASE_DIMS, combine_cases
from roughcontact.analysis.aggregate.derivatives import (
    fd_weights,
    load_derivative,
    log_window_edges,
    windowed_load_slope,
)
from roughcontact.analysis.aggregate.derived import add_derived, aggregate_contact
from roughcontact.analysis.aggregate.seeds import representativity_statistics, seed_statistics
from roughcontact.theory.laws import cel_area, cel_dpbar_dp0, cel_pressure


def _cases(**kw):
    args = dict(k_l=(4.0, 16.0), k_s=(32.0,), hurst=(0.36, 0.84), seeds=range(3),
                point_noise=1e-4, seed_scatter=0.02, rng_seed=3)
    args.update(kw)
    return simulate_cel_cases(**args)


def _rep_cases(k_l=(1.0, 4.0, 16.0), k_s=(32.0, 64.0), seeds=range(4)):
    dss, names = [], []
    rng = np.random.default_rng(0)
    for kl in k_l:
        for ks in k_s:
            for s in seeds:
                c = {"k_l": [kl], "k_s": [ks], "H": [0.8], "seed": np.array([s], dtype=np.int64)}
                dims = CASE_DIMS
                dss.append(xr.Dataset(
                    {"epsilon": (dims, np.full((1, 1, 1, 1), 0.3 / kl + 0.01 * rng.random()),
                                 {"units": "1/L", "long_name": "L2 error of the height PDF"}),
                     "rms_height": (dims, np.full((1, 1, 1, 1), 0.1), {"units": "L", "long_name": "rms height"})},
                    coords=c))
                names.append(f"rep/kl{kl:g}_ks{ks:g}_s{s}.nc")
    return dss, names


# ------------------------------------------------------------------- combining
def test_combine_builds_the_case_grid():
    dss, names = _cases()
    ds = combine_cases(dss, names)
    assert dict(ds.sizes) == {"k_l": 2, "k_s": 1, "H": 2, "seed": 3, "step": 30}
    assert ds["area_fraction"].dims == CASE_DIMS + ("step",)
    assert ds["rms_slope"].dims == CASE_DIMS
    assert ds["k_l"].dtype == np.float64 and ds["seed"].dtype == np.int64
    assert ds["iterations"].dtype == np.int64  # no holes: integers stay integers
    assert bool(ds["case_present"].all()) and ds.attrs["n_cases"] == 12
    assert ds.attrs["e_star"] == 1.0
    one = dss[5]
    got = ds["area_fraction"].sel(k_l=one.k_l.item(), k_s=one.k_s.item(), H=one.H.item(), seed=one.seed.item())
    np.testing.assert_array_equal(got.values, one["area_fraction"].values.ravel())


def test_combine_keeps_the_global_attrs_every_case_shares():
    """Kept: a value equal in every case (NaN included, a NaN is the same value); dropped: one that differs."""
    dss, names = _cases()
    dss = [ds.assign_attrs(tol=1e-8, note="same", missing=np.nan, grid=[1, 2], seed_attr=i)
           for i, ds in enumerate(dss)]
    dss[3] = dss[3].assign_attrs(note="other", grid=[1, 2, 3])
    attrs = combine_cases(dss, names).attrs
    assert attrs["tol"] == 1e-8 and np.isnan(attrs["missing"])
    assert not {"note", "grid", "seed_attr"} & set(attrs)


def test_combos_with_k_l_not_below_k_s_are_holes_not_errors():
    dss, names = _cases(k_l=(4.0, 16.0), k_s=(8.0, 32.0))  # (16, 8) is not a case
    ds = combine_cases(dss, names)
    hole = dict(k_l=16.0, k_s=8.0)
    assert not bool(ds["case_present"].sel(hole).any())
    assert int(ds["case_present"].sum()) == 3 * 2 * 3
    assert bool(ds["area_fraction"].sel(hole).isnull().all())
    assert ds["iterations"].dtype == np.float64  # holes force float for NaN
    assert not bool(ds["converged"].sel(hole).any())


def test_missing_expected_case_is_named():
    dss, names = _cases()
    with pytest.raises(ValueError, match=r"k_l=16\.0, k_s=32\.0, H=0\.84, seed=2"):
        combine_cases(dss[:-1], names[:-1])


def test_explicit_expected_list():
    dss, names = _cases()
    expected = [(d.k_l.item(), d.k_s.item(), d.H.item(), d.seed.item()) for d in dss]
    combine_cases(dss, names, expected=expected)
    with pytest.raises(ValueError, match="H=0.5"):
        combine_cases(dss, names, expected=expected + [(16.0, 32.0, 0.5, 0)])
    with pytest.raises(ValueError, match=f"{names[0]}.*not among the expected"):
        combine_cases(dss, names, expected=expected[1:])


def test_mismatched_step_coordinate_names_the_file():
    dss, names = _cases()
    dss[4] = dss[4].assign_coords(step=dss[4]["step"].values - 1)
    with pytest.raises(ValueError, match=f"{names[4]}.*step"):
        combine_cases(dss, names)


def test_missing_required_variable_names_the_file():
    dss, names = _cases()
    dss[2] = dss[2].drop_vars("area_fraction")
    with pytest.raises(ValueError, match=f"{names[2]}.*area_fraction"):
        combine_cases(dss, names)


def test_other_input_errors():
    dss, names = _cases()
    with pytest.raises(ValueError, match="already given"):
        combine_cases(dss + [dss[0]], names + ["copy.nc"])
    bad = dss[1].copy()
    bad.attrs["e_star"] = 2.0
    with pytest.raises(ValueError, match=f"{names[1]}.*e_star"):
        combine_cases([dss[0], bad], names[:2])
    with pytest.raises(ValueError, match="same length"):
        combine_cases(dss, names[:-1])
    with pytest.raises(ValueError, match="kind"):
        combine_cases(dss, names, kind="surface")
    two = xr.concat([dss[0], dss[1]], dim="seed")
    with pytest.raises(ValueError, match="length 2"):
        combine_cases([two], ["two.nc"])


# ------------------------------------------------------------- finite differences
def test_fd_weights_uniform_central():
    np.testing.assert_allclose(fd_weights(0.0, np.array([-1.0, 0.0, 1.0])), [-0.5, 0.0, 0.5], atol=1e-15)
    np.testing.assert_allclose(fd_weights(0.0, np.array([-2.0, -1.0, 0.0, 1.0, 2.0])),
                               [1 / 12, -2 / 3, 0.0, 2 / 3, -1 / 12], atol=1e-14)


def test_load_derivative_exact_on_polynomials():
    p = np.sort(np.random.default_rng(2).uniform(0.1, 1.0, 12))
    t = np.log(p)
    # order 2 in ln p0 is exact for quadratics in ln p0, order 4 for quartics
    f2 = 1 + 2 * t - 3 * t**2
    np.testing.assert_allclose(load_derivative(f2, p), (2 - 6 * t) / p, rtol=1e-9)
    f4 = f2 + 0.5 * t**3 - 0.2 * t**4
    np.testing.assert_allclose(load_derivative(f4, p, order=4), (2 - 6 * t + 1.5 * t**2 - 0.8 * t**3) / p,
                               rtol=1e-8)
    # order 2 in p0 is numpy.gradient(edge_order=2)
    g = np.sin(3 * p)
    np.testing.assert_allclose(load_derivative(g, p, variable="p0"), np.gradient(g, p, edge_order=2),
                               rtol=1e-12)


def test_load_derivative_rejects_bad_schedules():
    with pytest.raises(ValueError, match="strictly increasing"):
        load_derivative(np.ones(5), np.array([1.0, 2.0, 2.0, 3.0, 4.0]))
    with pytest.raises(ValueError, match="order"):
        load_derivative(np.ones(5), np.arange(1.0, 6.0), order=3)
    with pytest.raises(ValueError, match=">= 5 load steps"):
        load_derivative(np.ones(4), np.arange(1.0, 5.0), order=4)


# ------------------------------------------------------------------ derived data
def test_derived_quantities_on_noiseless_cel():
    dss, names = _cases(point_noise=0.0, seed_scatter=0.0, n_steps=60, seeds=range(2))
    agg = aggregate_contact(dss, names)
    a = agg["area_fraction"].isel(k_l=0, k_s=0, H=0, seed=0).values
    d = agg["dpbar_dp0"].isel(k_l=0, k_s=0, H=0, seed=0).values
    exact = cel_dpbar_dp0(a, mu=0.55, beta=0.21)
    # Second order in ln p0: ~1 % at the second step, < 0.5 % from the fourth on.
    assert np.max(np.abs(d[3:] / exact[3:] - 1)) < 5e-3
    agg4 = add_derived(combine_cases(dss, names), derivative_order=4)
    d4 = agg4["dpbar_dp0"].isel(k_l=0, k_s=0, H=0, seed=0).values
    assert np.max(np.abs(d4[2:] / exact[2:] - 1)) < 1e-3
    np.testing.assert_allclose(agg["kappa"], 0.1 * 1.0 / agg["mean_contact_pressure"], rtol=1e-14)
    assert float(agg["n_unconverged"].sum()) == 0
    for var in ("kappa", "dpbar_dp0", "n_unconverged", "case_present"):
        assert agg[var].attrs["units"] and agg[var].attrs["long_name"]


def test_unconverged_steps_are_counted():
    dss, names = _cases()
    conv = dss[3]["converged"].values.copy()
    conv[..., [4, 9]] = False
    dss[3]["converged"].values[...] = conv
    agg = aggregate_contact(dss, names)
    key = {d: dss[3][d].item() for d in CASE_DIMS}
    assert float(agg["n_unconverged"].sel(key)) == 2
    assert float(agg["n_unconverged"].sum()) == 2


def test_inconsistent_kappa_or_pressure_is_caught():
    dss, names = _cases()
    dss[1]["kappa"].values[..., 7] *= 1.01
    with pytest.raises(ValueError, match="stored kappa.*step"):
        aggregate_contact(dss, names)
    dss, names = _cases()
    dss[1]["mean_contact_pressure"].values[..., 7] *= 1.01
    with pytest.raises(ValueError, match="mean_contact_pressure"):
        aggregate_contact(dss, names)


def test_decreasing_load_is_rejected():
    dss, names = _cases()
    dss[0]["pressure"].values[..., 3] = dss[0]["pressure"].values[..., 1]
    ds = combine_cases(dss, names)
    with pytest.raises(ValueError, match="strictly increasing"):
        add_derived(ds.assign(mean_contact_pressure=ds["pressure"] / ds["area_fraction"]).drop_vars("kappa"))


# --------------------------------------------------------------- seed statistics
def test_seed_statistics_against_numpy():
    dss, names = _cases(k_l=(4.0, 16.0), k_s=(8.0, 32.0))
    agg = aggregate_contact(dss, names)
    st = seed_statistics(agg)
    for var in ("area_fraction", "kappa", "mean_contact_pressure", "dpbar_dp0"):
        vals = agg[var].sel(k_l=4.0, k_s=8.0, H=0.36).values  # (seed, step)
        np.testing.assert_allclose(st[f"{var}_mean"].sel(k_l=4.0, k_s=8.0, H=0.36), vals.mean(0), rtol=1e-13)
        std = vals.std(0, ddof=1)
        np.testing.assert_allclose(st[f"{var}_std"].sel(k_l=4.0, k_s=8.0, H=0.36), std, rtol=1e-10)
        np.testing.assert_allclose(st[f"{var}_sem"].sel(k_l=4.0, k_s=8.0, H=0.36), std / np.sqrt(3), rtol=1e-10)
        for suffix in ("mean", "std", "sem"):
            assert st[f"{var}_{suffix}"].attrs["units"] and st[f"{var}_{suffix}"].attrs["long_name"]
    assert int(st["n_seeds"].sel(k_l=4.0, k_s=8.0, H=0.36)) == 3
    assert int(st["n_seeds"].sel(k_l=16.0, k_s=8.0, H=0.36)) == 0
    assert bool(st["kappa_mean"].sel(k_l=16.0, k_s=8.0).isnull().all())
    assert st["pressure_mean"].attrs["units"] == "E*"


def test_nan_in_one_seed_propagates_to_that_step_only():
    dss, names = _cases()
    agg = aggregate_contact(dss, names)
    agg["area_fraction"][0, 0, 0, 1, 10] = np.nan
    st = seed_statistics(agg)
    m = st["area_fraction_mean"][0, 0, 0].values
    assert np.isnan(m[10]) and np.isfinite(np.delete(m, 10)).all()


def test_too_few_seeds_is_an_error_unless_allowed():
    dss, names = _cases(seeds=[0])
    agg = aggregate_contact(dss, names)
    with pytest.raises(ValueError, match="min_seeds"):
        seed_statistics(agg)
    st = seed_statistics(agg, min_seeds=1)
    assert bool(st["kappa_sem"].isnull().all()) and bool(st["kappa_mean"].notnull().all())


def test_representativity_statistics():
    dss, names = _rep_cases()
    ds = combine_cases(dss, names, kind="representativity")
    st = representativity_statistics(ds)
    eps = ds["epsilon"].sel(k_l=4.0, k_s=64.0, H=0.8).values
    assert float(st["epsilon_mean"].sel(k_l=4.0, k_s=64.0, H=0.8)) == pytest.approx(eps.mean())
    assert float(st["epsilon_sem"].sel(k_l=4.0, k_s=64.0, H=0.8)) == pytest.approx(eps.std(ddof=1) / 2)
    assert st["epsilon_mean"].attrs["units"] == "1/L"
    assert "rms_height_mean" in st and int(st["n_seeds"].min()) == 4
    with pytest.raises(ValueError, match="epsilon"):
        representativity_statistics(ds.drop_vars("epsilon"))
    with pytest.raises(ValueError, match="epsilon"):
        combine_cases([d.drop_vars("epsilon") for d in dss], names, kind="representativity")


# ------------------------------------------------------- windowed d pbar / d p0
def test_log_window_edges_sit_on_a_fixed_grid_and_merge_sparse_windows():
    a = np.array([0.011, 0.012, 0.02, 0.03, 0.031, 0.05, 0.07, 0.071, 0.09])
    e = log_window_edges(a, per_decade=6, min_points=1)
    np.testing.assert_allclose(np.log10(e) * 6, np.round(np.log10(e) * 6), atol=1e-9)  # on 10^(k/6)
    assert e[0] <= a.min() and e[-1] > a.max()
    merged = log_window_edges(a, per_decade=6, min_points=2)
    counts = np.histogram(a, bins=merged)[0]
    assert counts.min() >= 2 and counts.sum() == a.size
    assert set(np.round(np.log10(merged) * 6, 9)) <= set(np.round(np.log10(e) * 6, 9))
    with pytest.raises(ValueError, match="per_decade"):
        log_window_edges(a, per_decade=0)
    with pytest.raises(ValueError, match="min_points"):
        log_window_edges(a[:1], min_points=2)


def test_windowed_slope_is_exact_on_linear_and_quadratic_loads():
    """Linear pbar(p0): exact slope; quadratic on equal load steps: exact pbar' at the window's mean p0."""
    p0 = 0.005 * np.arange(1, 31) / 30
    area = 25.0 * p0  # A/A0 from 0.004 to 0.125, only assigns the windows
    edges = log_window_edges(area, 6)
    a_w, slope = windowed_load_slope(0.3 + 2.5 * p0, p0, area, edges)
    assert np.isfinite(slope).sum() >= 5
    np.testing.assert_allclose(slope[np.isfinite(slope)], 2.5, rtol=1e-10)
    a_w, slope = windowed_load_slope(0.3 + 2.5 * p0 - 40.0 * p0**2, p0, area, edges)
    ok = np.isfinite(slope)
    p_mean = a_w[ok] / 25.0  # area is linear in p0: mean area <-> mean p0
    np.testing.assert_allclose(slope[ok], 2.5 - 80.0 * p_mean, rtol=1e-10)
    # Leading axes are independent load curves; a NaN step drops out of its window only.
    pb = np.stack([0.3 + 2.5 * p0, 0.3 + 1.5 * p0])
    pb[1, -1] = np.nan
    _, s2 = windowed_load_slope(pb, p0, np.stack([area, area]), edges)
    assert s2.shape == (2, edges.size - 1)
    np.testing.assert_allclose(s2[0][np.isfinite(s2[0])], 2.5, rtol=1e-10)
    np.testing.assert_allclose(s2[1][np.isfinite(s2[1])], 1.5, rtol=1e-10)


def test_windowed_slope_recovers_the_cel_power_law():
    """On the noiseless CEL, pbar = p0 / (A/A0) has d pbar/d p0 = beta (A0/A)^mu exactly."""
    cel = {"kappa": 1.145 * np.sqrt(2 * np.pi), "mu": 0.55, "beta": 0.21, "rms_slope": 0.1, "e_star": 1.0}
    p0 = cel_pressure(0.15, **cel) * np.arange(1, 31) / 30
    a = cel_area(p0, **cel)
    a_w, slope = windowed_load_slope(p0 / a, p0, a, log_window_edges(a, 6))
    ok = np.isfinite(slope)
    assert ok.sum() >= 5 and a_w[ok].min() < 0.01
    np.testing.assert_allclose(slope[ok], cel_dpbar_dp0(a_w[ok], mu=0.55, beta=0.21), rtol=0.02)


def test_windowed_slope_needs_points_and_increasing_edges():
    p0 = np.arange(1.0, 6.0)
    a_w, slope = windowed_load_slope(p0, p0, 0.01 * p0, np.array([0.01, 0.015, 0.1]), min_points=2)
    assert np.isnan(slope[0]) and np.isnan(a_w[0]) and slope[1] == pytest.approx(1.0)  # 1 step, then 4
    with pytest.raises(ValueError, match="edges"):
        windowed_load_slope(p0, p0, p0, np.array([1.0, 0.5]))
    with pytest.raises(ValueError, match="min_points"):
        windowed_load_slope(p0, p0, p0, np.array([0.5, 1.0]), min_points=1)


@pytest.mark.parametrize("boundary", ["periodic", "free"])
def test_square_and_rectangular_cases_aggregate_with_every_label(boundary):
    # Measured files may be square or not, with square pixels or not: their per-case contact files
    # must stack along `topography` with every variable's units and long_name kept (a text that
    # differed between the two kinds of cell was once dropped as a conflict, and the aggregate refused).
    from roughcontact.analysis.aggregate.combine import combine_topographies
    from roughcontact.pipeline.datasets import contact_dataset
    from roughcontact.solver import solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    cells = {"square": ((32, 32), 1.0), "rect": ((32, 24), (1.0, 0.5))}
    parts = []
    for name, (shape, length) in cells.items():
        h = generate_surface(32, 2, 8, 0.8, 0, rms_slope=0.1)[:shape[0], :shape[1]].copy()
        result = solve_contact(h, [0.001, 0.002, 0.003], length=length, boundary=boundary)
        parts.append(contact_dataset(result, rms_slope=0.1, alpha=2.0, e_star=1.0, topography=name))
    agg = combine_topographies(parts, list(cells), expected=list(cells))
    for name, var in agg.data_vars.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
        texts = [{key: str(value) for key, value in v.attrs.items()} for v in (var, parts[0][name], parts[1][name])]
        assert texts[0] == texts[1] == texts[2], name

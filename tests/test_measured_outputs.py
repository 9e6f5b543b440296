"""Outputs of measured scenes: the pooled CEL fit of topographies, its table, figures and report table.

Test data follow the layout of a measured scene (cases named by strings along ``topography``):
the contact aggregate is cel_synthetic.simulate_cel_cases' synthetic CEL data for one
(k_l, k_s, H), its seeds renamed into named topographies; the surfaces are small generated maps
written as ``surfaces/{name}.nc`` with the measured statistics.
"""
import csv
import io

import numpy as np
import pytest
import xarray as xr
from docutils.core import publish_parts

from cel_synthetic import simulate_cel_cases
from roughcontact.analysis import fit
from roughcontact.analysis.aggregate.derived import aggregate_contact
from roughcontact.figures.measured import fig_measured_area_load, fig_measured_kappa, fig_topographies
from roughcontact.figures.registry import FIGURES, scene_figures
from roughcontact.figures.style import save_figure
from roughcontact.pipeline.io import read_dataset, write_dataset
from roughcontact.studies import report, report_tables
from roughcontact.surfaces.synthetic import generate_surface, spectral_moments

TRUTH = np.array([fit.PAPER_CEL[c][0] for c in fit.CONSTANTS])
NAMES = ["ground-a", "ground-b", "ground-c", "ground-d", "ground-e", "ground-f"]
MEASURED_FIGURES = ["topographies", "measured_area_load", "measured_kappa"]


def _cases(n=6, **kw):
    args = dict(seeds=range(n), point_noise=1e-3, seed_scatter=0.0, area_max=0.13, rng_seed=3)
    args.update(kw)
    return aggregate_contact(*simulate_cel_cases(**args))


def _measured(cases: xr.Dataset) -> xr.Dataset:
    """The one (k_l, k_s, H) of ``cases`` in a measured scene's layout: dims (topography, step)."""
    agg = cases.isel(k_l=0, k_s=0, H=0, drop=True).rename(seed="topography")
    agg = agg.assign_coords(topography=("topography", np.array(NAMES[:agg.sizes["topography"]], dtype=object),
                                        {"units": "1", "long_name": "name of the measured topography"}))
    agg["step"].attrs = {"units": "1", "long_name": "load step"}
    agg.attrs["boundary"] = "free"
    return agg


@pytest.fixture(scope="module")
def agg():
    return _measured(_cases())


@pytest.fixture(scope="module")
def result(agg):
    return fit.fit_topographies(agg, n_boot=40)


# ------------------------------------------------------------------------------------- the fit
def test_noiseless_topographies_give_back_the_constants():
    agg = _measured(_cases(n=2, point_noise=0.0))
    res = fit.fit_topographies(agg, n_boot=10)
    # The joint fit has nothing to average away: exact up to the optimiser's tolerance.
    np.testing.assert_allclose(res["value"].sel(estimator="joint").values, TRUTH, rtol=1e-8)
    # The paper route differentiates pbar numerically over 30 steps (see test_fit): kappa within
    # 0.2 %, mu within 0.004, beta within 0.003, the bias of its second-order differences.
    kappa, mu, beta = res["value"].sel(estimator="paper").values
    assert kappa == pytest.approx(TRUTH[0], rel=2e-3)
    assert mu == pytest.approx(TRUTH[1], abs=4e-3) and beta == pytest.approx(TRUTH[2], abs=3e-3)


def test_noisy_topographies_land_within_three_bootstrap_errors(agg, result):
    # 6 topographies x 30 steps with 0.1 % noise on A/A0: a calibrated, unbiased estimate lies within
    # 3 bootstrap standard errors of the truth with probability 0.997 (the draw is fixed, so the test is
    # deterministic). The paper route's differencing bias (~0.002 on mu) is well inside that (s.e. ~0.01).
    for estimator in ("paper", "joint"):
        value = result["value"].sel(estimator=estimator).values
        se = result["bootstrap_stderr"].sel(estimator=estimator).values
        assert np.all(se > 0), estimator
        assert np.all(np.abs(value - TRUTH) <= 3 * se), (estimator, value, se)
    assert int(result["n_topographies"]) == len(NAMES) and result["in_fit"].values.tolist() == [1] * len(NAMES)
    assert float(result["alpha_surfaces"]) == pytest.approx(float(agg["alpha"].mean()))
    assert "alpha_power_law" not in result and set(result["value"].dims) == {"estimator", "constant"}
    for name in list(result.data_vars) + list(result.coords):
        assert result[name].attrs["units"] == "1" and result[name].attrs["long_name"], name


def test_same_machinery_as_fit_cel(agg, result):
    # One (k_l, k_s, H) with the topographies as seeds: fit_cel's H-pooled group sees the same curves,
    # so the estimates agree exactly (only the bootstrap stream is keyed differently).
    cases = _cases()
    pooled = fit.fit_cel(cases, n_boot=10).sel(H_group=fit.POOLED).isel(k_l=0, k_s=0)
    for var in ("value", "stderr", "n_points"):
        np.testing.assert_array_equal(result[var].values, pooled[var].values, err_msg=var)
    # A load schedule given per step only, and kappa and d pbar/d p0 left to derive, change nothing.
    bare = agg.drop_vars(["kappa", "dpbar_dp0", "n_unconverged", "case_present"])
    bare["pressure"] = agg["pressure"].isel(topography=0, drop=True)
    np.testing.assert_array_equal(fit.fit_topographies(bare, n_boot=10)["value"].values, result["value"].values)


def test_bootstrap_needs_two_topographies(agg, result):
    lo, hi, value = (result[v].values for v in ("ci_low", "ci_high", "value"))
    assert np.all(lo < value) and np.all(value < hi)
    assert result["n_boot_ok"].values.tolist() == [40, 40]
    two = fit.fit_topographies(agg.isel(topography=[0, 3]), n_boot=10)
    assert np.all(np.isfinite(two["bootstrap_stderr"].values)) and int(two["n_topographies"]) == 2
    one = fit.fit_topographies(agg.isel(topography=[2]), n_boot=10)
    assert np.all(np.isfinite(one["value"].values)) and int(one["n_topographies"]) == 1
    for var in ("bootstrap_stderr", "ci_low", "ci_high"):
        assert np.all(np.isnan(one[var].values)), var
    assert one["n_boot_ok"].values.tolist() == [0, 0] and not one["constrained"].values.any()


def test_an_interval_on_its_estimate_is_not_constrained():
    """Two topographies: the bootstrap draws (a, b) and (b, a) refit the estimate itself, so the percentile
    interval often ends on it (two real line scans gave kappa = 108.7 [7.09, 108.68], flagged "yes"); the data
    do not bound the constant on that side."""
    result = fit.fit_topographies(_measured(_cases(n=2, rng_seed=0, seed_scatter=0.05)), n_boot=20)
    value, low, high = (result[k].sel(estimator="paper").values for k in ("value", "ci_low", "ci_high"))
    touching = np.isclose(low, value, rtol=fit.TOUCH_RTOL, atol=0) | np.isclose(high, value, rtol=fit.TOUCH_RTOL,
                                                                                 atol=0)
    assert touching.any(), "this draw is meant to give an interval on its estimate"
    assert not result["constrained"].sel(estimator="paper").values[touching].any()
    rows = [r for r in csv.DictReader(io.StringIO(fit.to_csv_table(result))) if r["estimator"] == "paper"]
    assert all(r["constrained"] == "no" for r, t in zip(rows, touching, strict=True) if t)


def test_unconverged_topographies_are_excluded_by_name(agg):
    bad = agg.drop_vars(["n_unconverged", "case_present"])
    bad["converged"] = bad["converged"].copy()
    bad["converged"].loc[{"topography": "ground-b", "step": 7}] = False
    kept, excluded = fit.exclude_unconverged(bad)
    assert excluded == ["ground-b"]
    assert kept["case_present"].values.tolist() == [True, False, True, True, True, True]
    assert kept["case_present"].attrs["units"] == "1" and kept["case_present"].attrs["long_name"]
    res = fit.fit_topographies(kept, n_boot=10)
    assert int(res["n_topographies"]) == 5 and res["in_fit"].sel(topography="ground-b") == 0
    assert fit.exclude_unconverged(agg)[1] == []
    # every topography excluded: no fit, an empty table, and no error
    none = fit.fit_topographies(agg.assign(case_present=agg["case_present"] & False), n_boot=10)
    assert int(none["n_topographies"]) == 0 and np.all(np.isnan(none["value"].values))
    assert fit.to_csv_table(none).count("\n") == 1


def test_wrong_layouts_are_refused(agg):
    with pytest.raises(ValueError, match=r"dims \(topography, step\)"):
        fit.fit_topographies(_cases(n=2), n_boot=10)
    with pytest.raises(ValueError, match="window"):
        fit.fit_topographies(agg, window=(0.2, 0.1), n_boot=10)
    with pytest.raises(ValueError, match="fit_topographies.*window"):
        fit.fit_topographies(agg, window=(0.5, 0.6), n_boot=10, on_insufficient="raise")


def test_csv_table_has_one_pooled_group(result):
    text = fit.to_csv_table(result)
    rows = list(csv.DictReader(io.StringIO(text)))
    assert text.splitlines()[0].split(",") == list(fit.TOPOGRAPHY_CSV_COLUMNS)
    assert [(r["estimator"], r["constant"]) for r in rows] == [
        (e, c) for e in ("paper", "joint") for c in fit.CONSTANTS]
    assert {r["group"] for r in rows} == {"pooled (6 topographies)"}
    assert {r["n_topographies"] for r in rows} == {"6"} and {r["n_boot_ok"] for r in rows} == {"40"}
    kappa = rows[0]
    assert float(kappa["value"]) == pytest.approx(float(result["value"].sel(estimator="paper", constant="kappa")),
                                                  rel=1e-5)
    assert kappa["constrained"] == "yes" and kappa["ci_low"] and kappa["paper_value"] == "2.87009"


# ------------------------------------------------------------------------------------- figures
def _surface(name: str, seed: int) -> xr.Dataset:
    """A 64 x 64 map in the layout of results/{scene}/surfaces/{name}.nc (heights in um)."""
    length = 100.0
    heights = generate_surface(64, 4, 32, 0.8, seed, rms_height=1.5, length=length)
    stats = spectral_moments(heights, length)
    x = np.arange(64) * length / 64
    one = {"topography": [name]}

    def scalar(key, units, long_name):
        return ("topography", [stats[key]], {"units": units, "long_name": long_name})

    return xr.Dataset(
        {"heights": (("x", "y"), heights, {"units": "um", "long_name": "surface height h(x, y)"}),
         "rms_height": scalar("rms_height", "um", "rms height"), "rms_slope": scalar("rms_slope", "1", "rms slope"),
         "alpha": scalar("alpha", "1", "Nayak bandwidth"), "m0": scalar("m0", "um^2", "profile moment m0"),
         "m2": scalar("m2", "1", "profile moment m2"), "m4": scalar("m4", "um^-2", "profile moment m4")},
        coords={"x": ("x", x, {"units": "um", "long_name": "position along x"}),
                "y": ("y", x.copy(), {"units": "um", "long_name": "position along y"}),
                "topography": ("topography", np.array(one["topography"], dtype=object),
                               {"units": "1", "long_name": "name of the measured topography"})},
        attrs={"length": length, "n": 64, "source_file": f"data/{name}.x3p", "length_units": "um"})


def _scene(names, contact=True) -> dict:
    """A validated measured scene, as roughcontact.pipeline.config leaves it."""
    scene = {"description": "measured", "topography": {"files": {n: {"path": f"data/{n}.x3p"} for n in names},
                                                       "unit": "um", "undefined": "reject"},
             "representativity": {"n_bins": 100}, "fit": {"window": [0.01, 0.11], "n_boot": 40}}
    if contact:
        scene["contact"] = {"load": {"p_max": 0.005, "n_steps": 30}, "solver": {"e_star": 1.0, "boundary": "free"}}
    return scene


@pytest.fixture(scope="module")
def scene_dir(tmp_path_factory, agg, result):
    """results/{scene}/ of a measured scene with three topographies, written as the workflow writes them."""
    names = NAMES[:3]
    root = tmp_path_factory.mktemp("measured") / "results" / "measured"
    sub = agg.isel(topography=[0, 1, 2])
    sub["alpha"] = sub["alpha"] * 0 + np.array([4.0, 5.0, 6.0])  # as measured: each surface its own bandwidth
    for i, name in enumerate(names):
        write_dataset(_surface(name, i), root / "surfaces" / f"{name}.nc", stage="surface", scene="measured",
                      scene_parameters={"topography": {"unit": "um"}})
    write_dataset(sub, root / "aggregate" / "contact.nc", stage="aggregate", scene="measured",
                  scene_parameters={"solver": {"boundary": "free"}})
    res = fit.fit_topographies(sub, n_boot=10)
    for var in res.data_vars:
        if res[var].dtype.kind == "f":
            res[var].attrs["allow_nan"] = 1
    write_dataset(res, root / "fit" / "cel.nc", stage="fit", scene="measured", scene_parameters={})
    return root, _scene(names)


def _render(name, scene_dir):
    root, scene = scene_dir
    paths = {role: [str(root / p) for p in v] if isinstance(v, list) else str(root / v)
             for role, v in FIGURES[name].input_paths(scene).items()}
    return FIGURES[name].render(paths)


@pytest.mark.parametrize("name", MEASURED_FIGURES)
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_figures_render_from_the_scene_files_and_save_byte_identically(name, scene_dir, tmp_path):
    fig = _render(name, scene_dir)
    title = fig._suptitle.get_text()
    assert ("3 measured topographies" if name == "topographies" else "3 topographies, $N = 64$, free boundary") \
        in title, title
    first = save_figure(fig, tmp_path / "a" / name)
    second = save_figure(_render(name, scene_dir), tmp_path / "b" / name)
    for a, b in zip(first, second, strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name
    for ax in fig.axes:
        if ax.get_visible() and ax.has_data():
            assert ax.get_xlabel(), name


def test_figure_contents(agg, result):
    fig = fig_measured_area_load(agg, result)
    ax = fig.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels[:len(NAMES)] == NAMES
    assert any("CEL fitted to the 6 topographies (joint least squares)" in t for t in labels)
    assert any("BGT small-load limit" in t for t in labels) and any("Persson, full" in t for t in labels)
    assert "$p_0/E^*$ = " in fig._suptitle.get_text()
    # without a fit, and with a topography left out of it
    one_bad = agg["n_unconverged"] + (agg["topography"] == "ground-c")
    kept, _ = fit.exclude_unconverged(agg.assign(n_unconverged=one_bad))
    labels = [t.get_text() for t in fig_measured_kappa(kept).legends[0].get_texts()]
    assert "ground-c (not in the fit)" in labels and not any("fitted" in t for t in labels)
    single = fig_topographies([_surface("ground-a", 0)])
    assert "$N$ = 64" in single.axes[0].get_title() and "1 measured topography" in single._suptitle.get_text()
    with pytest.raises(ValueError, match="topography"):
        fig_measured_kappa(_cases(n=2))


def test_loads_beyond_an_asperity_model_leave_it_cut_not_the_figure_failed(agg, result):
    # A surface of rms slope 0.003 pushed to p0/E* = 0.005 reaches p0/(E* h') ~ 1.7, beyond where
    # BGT and Greenwood reach full contact (their tables end there): the figure once failed with
    # "p0 (= E* h' pbar; ...) must be finite and lie in [0, 1.79]"; the models are now drawn up to
    # their full contact, with a note in the legend.
    from roughcontact.theory.asperity import asperity_max_load

    alpha = float(np.median(agg["alpha"].values))
    limit = min(asperity_max_load(alpha=alpha, rms_slope=1.0, e_star=1.0, model=m) for m in ("bgt", "greenwood"))
    steep = agg.assign(rms_slope=agg["rms_slope"] * 0 + float(agg["pressure"].max()) / (2.0 * limit))
    labels = [t.get_text() for t in fig_measured_area_load(steep, result).legends[0].get_texts()]
    assert "BGT, Greenwood: drawn up to their full contact" in labels
    assert "BGT, Greenwood: drawn up to their full contact" not in [
        t.get_text() for t in fig_measured_area_load(agg, result).legends[0].get_texts()]


def test_a_measured_scene_gets_exactly_the_measured_figures():
    scene = _scene(["ground-b", "ground-a"])
    assert scene_figures(scene) == MEASURED_FIGURES
    assert scene_figures(_scene(["ground-a"], contact=False)) == ["topographies"]
    surfaces = ["surfaces/ground-a.nc", "surfaces/ground-b.nc"]  # sorted by name
    assert FIGURES["topographies"].input_paths(scene) == {"surfaces": surfaces}
    assert FIGURES["measured_kappa"].input_paths(scene) == {
        "agg": "aggregate/contact.nc", "fit": "fit/cel.nc", "surfaces": surfaces}
    # and a generated scene none of them
    generated = {"contact": {"grid": {"k_l": ["16"], "k_s": ["32"], "H": ["0.8"]}}}
    assert scene_figures(generated) == ["area_load", "kappa", "dpbar"]
    assert FIGURES["kappa"].input_paths(generated) == {"agg": "aggregate/contact.nc", "fit": "fit/cel.nc"}


def test_surface_files_round_trip(scene_dir):
    root, _ = scene_dir
    ds = read_dataset(root / "surfaces" / "ground-b.nc", stage="surface", variables=["heights", "alpha"])
    assert ds.attrs["length_units"] == "um" and str(ds["topography"].values[0]) == "ground-b"


# ------------------------------------------------------------------------------------- report
def _html(rst: str) -> str:
    html = publish_parts(rst, writer="html", settings_overrides={"report_level": 1, "halt_level": 2})["body"]
    assert "system-message" not in html, html
    return html


def test_report_fit_table_of_a_measured_scene(agg, result):
    csv_text = fit.to_csv_table(result)
    rows = report.read_fit_csv(csv_text)
    assert report.is_measured_fit(rows)
    html = _html(report.fit_table(csv_text))
    assert html.count("<tr") == 1 + 2 + 1  # header, paper and joint, published
    for row in rows:  # each constant rounded to its interval (kappa as kappa/sqrt(2 pi))
        assert report.constant_estimate(row)[0] in html, row
    assert "pooled (6 topographies)" in html and "topographies</th>" in html and "1.145 ± 0.002" in html
    assert "*" not in html and "†" not in html
    one = _html(report.fit_table(fit.to_csv_table(fit.fit_topographies(agg.isel(topography=[0]), n_boot=10))))
    assert "pooled (1 topography)" in one and one.count(" †") == 6 and "a single topography" in one
    summary = _html(report.summary_rst("measured", {"fit": {"n_boot": 40}}, fit_csv=csv_text))
    assert "all measured topographies pooled" in summary and "pooled (6 topographies)" in summary
    with pytest.raises(ValueError, match="n_topographies"):
        report.fit_table(csv_text.replace("n_topographies", "n_surfaces"))


def test_report_lists_every_topography_with_its_loads(scene_dir):
    root, scene = scene_dir
    agg = read_dataset(root / "aggregate" / "contact.nc", stage="aggregate")
    rows = []
    for name in scene["topography"]["files"]:
        surface = read_dataset(root / "surfaces" / f"{name}.nc", stage="surface")
        surface.attrs["source"] = f'{{"file": "data/{name}.x3p"}}'
        rows.append(report_tables.topography_row(name, surface, agg.sel(topography=name)))
    tables = report_tables.topographies_table(rows)
    html = _html(report.summary_rst("measured", {"fit": {"n_boot": 40}}, topographies=tables))
    tables = html.split("Topographies</h")[1].split("Parameters of scene")[0]
    assert "Topographies</h" in html and tables.count("<tr") == 1 + 3
    for name, row in zip(scene["topography"]["files"], rows, strict=True):
        assert f">{name}<" in html and f"{name}.x3p" in html and "64 x 64" in row[2]
        assert row[-1] == "30 of 30" and float(row[-2]) == pytest.approx(
            float(agg["area_fraction"].sel(topography=name).isel(step=-1)), rel=1e-2)
    # without a contact study: the load columns stay empty
    assert report_tables.topography_row("ground-a", surface)[-3:] == ["", "", ""]


def test_rectangular_maps_are_drawn_to_scale_with_both_sides():
    # A map kept whole (nx != ny, dx != dy): drawn over Lx x Ly, its title giving both sides and
    # counts, and the area-load title the range of grids.
    from roughcontact.figures.measured import grid_text
    from roughcontact.pipeline.datasets import measured_surface_dataset
    from roughcontact.surfaces.topography import MeasuredSurface

    h = generate_surface(64, 4, 32, 0.8, 0, rms_height=1.5)[:64, :40].copy()
    ds = measured_surface_dataset(MeasuredSurface(h, (30000.0, 7500.0), "um", {}), name="frt-2")
    assert ds.attrs["length_x"] == 30000.0 and ds.attrs["ny"] == 40 and "length" not in ds.attrs
    ax = fig_topographies([ds]).axes[0]
    assert r"$3e+04" not in ax.get_title() and r"$3.0e+04" not in ax.get_title()
    assert r"$30000 \times 7500$" in ax.get_title() and r"$64 \times 40$" in ax.get_title()
    assert ax.get_images()[0].get_extent() == [0.0, 30000.0, 0.0, 7500.0]
    grids = {"a": (150, 300), "b": (256, 256), "c": (650, 650)}
    assert grid_text(grids) == r"grids $150 \times 300$ to $650 \times 650$"
    assert grid_text({"a": (256, 256), "b": (64, 64)}) == "$N$ = 64-256"


def _rescaled(agg, factors):
    """``agg`` with each topography's rms slope, loads and contact pressures times its factor:
    the same curves in p0 / (E* h'), as files of different slopes loaded relative to them."""
    f = xr.DataArray(np.asarray(factors, float), dims="topography", coords={"topography": agg["topography"]})
    out = agg.drop_vars([v for v in ("kappa", "dpbar_dp0") if v in agg])
    for var in ("rms_slope", "pressure", "mean_contact_pressure"):
        out[var] = (out[var] * f).assign_attrs(agg[var].attrs)
    return out


def test_files_loaded_relative_to_their_slopes_average_like_seeds(agg, result):
    """The topography-mean curve needs one schedule p0 / (E* h'), not one p0 (load.relative_to: rms_slope)."""
    scaled = _rescaled(agg, [1.0, 0.03, 2.0, 0.5, 10.0, 0.2])
    again = fit.fit_topographies(scaled, n_boot=40)
    np.testing.assert_allclose(again["value"].values, result["value"].values, rtol=1e-7)
    assert again.attrs["paper_average"] == "seeds"
    # the loads scaled but not the slopes: different normalised schedules, named, and "auto" stops averaging
    shifted = _rescaled(agg, [1.0, 1.1, 1.0, 1.0, 1.0, 1.0]).assign(rms_slope=agg["rms_slope"])
    with pytest.raises(ValueError, match=r"different load schedules p0/\(E\* h'\).*relative_to: rms_slope"):
        fit.fit_topographies(shifted, n_boot=10)
    auto = fit.fit_topographies(shifted, n_boot=10, paper_average="auto")
    assert auto.attrs["paper_average"] == "none" and np.all(np.isfinite(auto["value"].values))

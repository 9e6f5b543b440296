"""The contact map (issue 49 item 4): the stored fields drawn over the heights, 2-D maps and 1-D profiles, and
the figure planned only where a scene stores fields (``contact.outputs.fields``)."""
import copy

import numpy as np
import pytest
import xarray as xr

from caption_check import assert_caption_says_the_record, assert_caption_true, lead_of
from roughcontact.figures.captions import caption
from roughcontact.figures.contact_map import (
    MAP_CASES,
    MAP_STEPS,
    case_values,
    deformed_surface,
    fig_contact_maps,
    in_contact,
    shown_steps,
    stored_steps,
)
from roughcontact.figures.record import figure_record
from roughcontact.figures.registry import FIGURES, scene_figures
from roughcontact.figures.style import save_figure
from roughcontact.pipeline.config.schema import load_schema
from roughcontact.pipeline.datasets import contact_dataset, surface_dataset
from roughcontact.pipeline.scenes import validate_config
from roughcontact.solver import solve_contact
from roughcontact.surfaces.synthetic import generate_surface

STEPS = [2, 4]
LOADS = [0.005 * (i + 1) / 4 for i in range(4)]


def _case_2d(k_l: str, hurst: str, seed: int = 0, store=STEPS) -> tuple[xr.Dataset, xr.Dataset]:
    """A generated case as the pipeline writes it: its surface file's and contact file's datasets (N = 32, um)."""
    h = generate_surface(32, int(k_l), 8, float(hurst), seed=seed, rms_slope=0.1)
    res = solve_contact(h, LOADS, store_fields=store, length_unit="um")
    surface = surface_dataset(h, k_l=k_l, k_s="8", hurst=hurst, seed=seed, length=1.0,
                              normalisation={"rms_slope": 0.1}, length_unit="um")
    contact = contact_dataset(res, rms_slope=0.1, alpha=2.0, e_star=1.0, k_l=k_l, k_s="8", hurst=hurst, seed=seed)
    return surface, contact


@pytest.fixture(scope="module")
def cases_2d():
    return [_case_2d("2", "0.5"), _case_2d("4", "0.8")]


def _case_1d(case_dims: bool = True) -> tuple[xr.Dataset, xr.Dataset]:
    """A made-up 1-D case (a line scan): heights (x,), fields (field_step, x) at steps 2 and 4, no y dimension.

    A rigid flat lowered onto a two-mode profile: gap = max(d_k - h, 0) and a pressure on the nodes it touches,
    more of them at step 4."""
    nx = 64
    x = np.arange(nx) / nx
    h = 0.01 * np.cos(2 * np.pi * x) + 0.004 * np.sin(6 * np.pi * x)
    flats = {2: 0.011, 4: 0.008}
    gap = np.stack([np.maximum(flats[k] - h, 0.0) for k in STEPS])
    pressure = np.stack([np.where(g == 0.0, 0.02 + h - h.min(), 0.0) for g in gap])
    coords = {"x": ("x", x, {"units": "um"}), "field_step": ("field_step", STEPS), "step": ("step", [1, 2, 3, 4])}
    contact = xr.Dataset(
        {"contact_pressure": (("field_step", "x"), pressure, {"units": "1"}),
         "gap": (("field_step", "x"), gap, {"units": "um"}),
         "pressure": ("step", np.array(LOADS)), "area_fraction": ("step", np.array([0.01, 0.02, 0.03, 0.05]))},
        coords=coords, attrs={"e_star": 1.0})
    surface = xr.Dataset({"heights": ("x", h, {"units": "um"})}, coords={"x": coords["x"]})
    if case_dims:  # the files' length-1 case dimensions
        contact, surface = (ds.expand_dims(topography=["scan-1"]) for ds in (contact, surface))
    return surface, contact


# ------------------------------------------------------------------------------------- 2-D maps
def test_one_map_per_case_and_stored_step_with_the_pressure_only_on_the_contact_patches(cases_2d):
    fig = fig_contact_maps(cases_2d)
    maps = [ax for ax in fig.axes if len(ax.images) == 2]
    assert len(maps) == len(cases_2d) * len(STEPS)
    for i, (surface, contact) in enumerate(cases_2d):
        for j, step in enumerate(STEPS):
            ax = maps[i * len(STEPS) + j]
            heights_img, pressure_img = ax.images
            p = case_values(contact["contact_pressure"], step)
            np.testing.assert_array_equal(heights_img.get_array().T, case_values(surface["heights"]))
            # coloured exactly where p > 0; the rest of the map shows the grey heights under it
            shown = pressure_img.get_array()
            np.testing.assert_array_equal(~np.ma.getmaskarray(shown).T, p > 0)
            np.testing.assert_array_equal(shown.compressed(), p.T[p.T > 0])
            area = float(contact["area_fraction"].sel(step=step).squeeze())
            assert f"step {step}:" in ax.get_title() and f"{area:.3g}" in ax.get_title()
            assert f"{LOADS[step - 1]:.3g}" in ax.get_title()
    # one pressure scale for the figure (0 to the largest drawn p/E*), one height colour bar per case, with units
    assert len({(ax.images[1].norm.vmin, ax.images[1].norm.vmax) for ax in maps}) == 1
    top = max(float(c["contact_pressure"].max()) for _, c in cases_2d)
    assert maps[0].images[1].norm.vmax == pytest.approx(top)
    labels = [ax.get_ylabel() for ax in fig.axes if ax not in maps] + [ax.get_xlabel() for ax in fig.axes]
    assert sum("height $h$ [$\\mathrm{\\mu m}$]" in t for t in labels) == len(cases_2d)
    assert any("contact pressure $p/E^*$ [1] (where $p > 0$: the contact patches)" in t for t in labels)
    assert maps[0].get_xlabel() == "$x$ [$\\mathrm{\\mu m}$]"


def test_a_map_without_contact_draws_no_pressure():
    p = np.array([[0.0, -0.0], [0.0, 0.0]])
    assert in_contact(p).mask.all()
    assert in_contact(np.array([0.0, 1e-300, -1.0])).mask.tolist() == [True, False, True]


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_the_figure_and_its_caption_are_reproducible_and_true(cases_2d, tmp_path):
    fig = fig_contact_maps(cases_2d)
    # the figure draws no reference line: its caption is the lead and the notes of a 2-D map's layout
    record = figure_record("contact_map", fig)
    text = caption(lead_of("contact_map"), record)
    assert assert_caption_true(fig, text) == [] and record["notes"] == ["rows_of_steps", "maps"]
    assert_caption_says_the_record(record, text)
    first = save_figure(fig, tmp_path / "a" / "contact_map")
    second = save_figure(fig_contact_maps(cases_2d), tmp_path / "b" / "contact_map")
    for a, b in zip(first, second, strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name


def _big_map_case(n: int = 520) -> tuple[xr.Dataset, xr.Dataset]:
    """A made-up 2-D case of ``n x n`` points (more than MAP_PIXELS a side: drawn block-averaged), fields at step 2."""
    rng = np.random.default_rng(0)
    x = np.arange(n) / n
    coords = {"x": ("x", x, {"units": "um"}), "y": ("y", x.copy(), {"units": "um"}), "field_step": [2], "step": [1, 2]}
    heights = rng.standard_normal((n, n))
    pressure = np.where(heights > 2.0, heights, 0.0)[None]
    contact = xr.Dataset({"contact_pressure": (("field_step", "x", "y"), pressure), "gap": (("field_step", "x", "y"),
                          np.maximum(2.0 - heights, 0.0)[None]), "pressure": ("step", [0.001, 0.002]),
                          "area_fraction": ("step", [0.01, 0.02])}, coords=coords, attrs={"e_star": 1.0})
    return xr.Dataset({"heights": (("x", "y"), heights, {"units": "um"})}, coords=coords), contact


@pytest.mark.parametrize("kind", ["maps", "big maps", "side by side", "profiles"])
def test_the_caption_says_the_layout_drawn_and_block_averaging_only_where_it_happened(kind, cases_2d):
    """The caption described the 1-D layout and 512-point block averaging on the demo's 2-D maps of 256 points
    (issue 60): the lead holds what every rendering shows, the record adds the layout drawn, block averaging
    where a map was larger than MAP_PIXELS, and what profiles mean."""
    cases = {"maps": cases_2d, "big maps": [_big_map_case()],
             "side by side": [_case_2d("2", "0.5", store=[4]), _case_2d("4", "0.8", store=[4])],
             "profiles": [_case_1d()]}[kind]
    record = figure_record("contact_map", fig_contact_maps(cases))
    text = caption(lead_of("contact_map"), record)
    assert_caption_says_the_record(record, text)
    two_d = kind != "profiles"
    assert ("grey-scale" in text) == two_d and ("deformed surface" in text) == (not two_d)
    assert ("1-D" in text) == (not two_d) and record["profiles"] == (not two_d)
    assert ("block-averaged" in text) == (kind == "big maps"), text
    assert ("side by side" in text) == (kind in ("side by side", "big maps"))  # one stored step each


def test_many_stored_steps_and_cases_are_capped():
    assert shown_steps([3, 12]) == [3, 12]
    assert shown_steps(list(range(1, 31))) == [1, 11, 20, 30]
    assert len(shown_steps(list(range(1, 31)))) == MAP_STEPS
    surface, contact = _case_2d("2", "0.5", store=True)  # every step stored: dimension `step`
    assert stored_steps(contact) == [1, 2, 3, 4]
    fig = fig_contact_maps([(surface, contact)] * (MAP_CASES + 2))
    assert len([ax for ax in fig.axes if len(ax.images) == 2]) == MAP_CASES * 4


def test_one_stored_step_puts_the_cases_side_by_side_each_named():
    cases = [_case_2d("2", "0.5", store=[4]), _case_2d("4", "0.8", store=[4])]
    maps = [ax for ax in fig_contact_maps(cases).axes if len(ax.images) == 2]
    assert len(maps) == 2 and maps[0].get_position().y0 == pytest.approx(maps[1].get_position().y0)
    assert "$k_l$ = 2, $k_s$ = 8, $H$ = 0.5\nseed 0, step 4\n$A/A_0$" in maps[0].get_title()
    assert "$k_l$ = 4" in maps[1].get_title() and maps[1].get_ylabel() == ""


def test_bad_cases_are_named(cases_2d):
    with pytest.raises(ValueError, match="cases is empty"):
        fig_contact_maps([])
    surface, contact = cases_2d[0]
    with pytest.raises(ValueError, match="lacks variable"):
        fig_contact_maps([(surface, contact.drop_vars("gap"))])
    with pytest.raises(ValueError, match="mix 1-D profiles and 2-D maps"):
        fig_contact_maps([cases_2d[0], _case_1d()])
    with pytest.raises(ValueError, match="store different steps"):
        fig_contact_maps([cases_2d[0], _case_2d("4", "0.8", store=[4])])
    with pytest.raises(ValueError, match="step 3 is not stored"):
        case_values(contact["contact_pressure"], 3)


# ------------------------------------------------------------------------------------- 1-D profiles
@pytest.mark.parametrize("case_dims", [True, False])
def test_a_profile_shows_heights_deformed_surface_and_pressure(case_dims):
    surface, contact = _case_1d(case_dims)
    fig = fig_contact_maps([(surface, contact)])
    assert not any(ax.images for ax in fig.axes)
    profiles = [ax for ax in fig.axes if len(ax.lines) >= 3]
    pressures = [ax for ax in fig.axes if ax.collections]
    assert len(profiles) == len(pressures) == len(STEPS)
    h = case_values(surface["heights"])
    for ax, ax_p, step in zip(profiles, pressures, STEPS, strict=True):
        g, p = case_values(contact["gap"], step), case_values(contact["contact_pressure"], step)
        lines = {line.get_label(): line for line in ax.lines}
        np.testing.assert_array_equal(lines["profile $h(x)$"].get_ydata(), h)
        z, plane = deformed_surface(h, g)
        np.testing.assert_allclose(lines["deformed surface $d - g(x)$"].get_ydata(), plane - g)
        # marked in contact exactly where p > 0, and there the deformed surface is on the flat
        touching = np.asarray(lines["in contact ($p > 0$)"].get_ydata(), dtype=float)
        np.testing.assert_array_equal(np.isfinite(touching), p > 0)
        np.testing.assert_allclose(touching[p > 0], plane)
        assert f"step {step}:" in ax.get_title()
        # the pressure below: zero out of contact, p/E* where in contact
        path = ax_p.collections[0].get_paths()[0].vertices
        assert path[:, 1].max() == pytest.approx(p.max()) and path[:, 1].min() == 0.0
        assert ax_p.get_ylabel() in ("", r"$p/E^*$ [1]") and ax_p.get_xlabel() == "$x$ [$\\mathrm{\\mu m}$]"
    assert {t.get_text() for t in fig.legends[0].get_texts()} >= {"rigid flat $z = d$", "in contact ($p > 0$)"}


def test_a_profile_written_without_coordinates_draws_over_the_node_numbers():
    surface, contact = _case_1d(case_dims=False)
    contact, surface = contact.drop_vars("x"), surface.drop_vars("x")
    fig = fig_contact_maps([(surface, contact.assign_attrs(length_units="um"))])
    line = next(ax for ax in fig.axes if len(ax.lines) >= 3).lines[0]
    np.testing.assert_array_equal(line.get_xdata(), np.arange(64))


def test_the_deformed_surface_keeps_the_profile_mean_and_touches_the_flat_where_the_gap_is_zero():
    h = np.array([0.0, 1.0, 3.0, 1.0])
    g = np.array([2.0, 1.0, 0.0, 1.0])
    z, plane = deformed_surface(h, g)
    assert plane == pytest.approx(h.mean() + g.mean())
    assert z.mean() == pytest.approx(h.mean()) and z[2] == plane
    with pytest.raises(ValueError, match="one shape"):
        deformed_surface(h, g[:3])


# ------------------------------------------------------------------------------------- the registry
def test_the_contact_map_is_planned_only_where_fields_are_stored(shipped_config):
    scenes = validate_config(shipped_config, load_schema())["scenes"]
    demo = scenes["demo"]
    assert "contact_map" in scene_figures(demo) and "measured_contact_map" not in scene_figures(demo)
    assert "contact_map" not in scene_figures(scenes["representative"])
    cfg = copy.deepcopy(shipped_config)
    cfg["scenes"]["demo"]["contact"]["outputs"]["fields"] = []
    assert "contact_map" not in scene_figures(validate_config(cfg, load_schema())["scenes"]["demo"])
    # seed 0 of each (k_l, k_s, H): its surface (heights) and its contact file (fields), in one order
    stems = ["kl4_ks32_H0.36_s0", "kl4_ks32_H0.84_s0", "kl16_ks32_H0.36_s0", "kl16_ks32_H0.84_s0"]
    assert FIGURES["contact_map"].input_paths(demo) == {"surfaces": [f"surfaces/{s}.nc" for s in stems],
                                                        "contact": [f"contact/{s}.nc" for s in stems]}
    # a patch source's scene (files named by strings): each file, sorted, at most MAP_CASES
    names = ["f", "e", "d", "c", "b", "a"]
    patches = {"array": {"files": {n: {"path": f"{n}.npy"} for n in names}, "unit": "um"},
               "contact": {"outputs": {"fields": [3]}}}
    assert "measured_contact_map" in scene_figures(patches) and "contact_map" not in scene_figures(patches)
    assert FIGURES["measured_contact_map"].input_paths(patches)["contact"] == [
        f"contact/{n}.nc" for n in ["a", "b", "c", "d"]]
    assert "measured_contact_map" not in scene_figures({**patches, "contact": {"outputs": {"fields": []}}})
    assert "measured_contact_map" not in scene_figures({k: v for k, v in patches.items() if k != "contact"})


def test_the_registered_figure_renders_from_the_files(cases_2d, tmp_path):
    paths = {"surfaces": [], "contact": []}
    for i, (surface, contact) in enumerate(cases_2d):
        for role, stage, ds in (("surfaces", "surface", surface), ("contact", "contact", contact)):
            path = tmp_path / f"{role}_{i}.nc"
            ds.assign_attrs(roughcontact_stage=stage).to_netcdf(path, engine="netcdf4")
            paths[role].append(str(path))
    fig = FIGURES["contact_map"].render(paths)
    assert len([ax for ax in fig.axes if len(ax.images) == 2]) == len(cases_2d) * len(STEPS)

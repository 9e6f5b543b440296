"""The accuracy study: settings, metrics, the perimeter correction, and a tiny end-to-end run."""
import numpy as np
import pytest
import xarray as xr

from conftest import ACCURACY, run_snakemake
from roughcontact import generate_surface
from roughcontact.solver import solve_contact
from roughcontact.studies import accuracy
from roughcontact.theory.perimeter import perimeter_corrected_area

ACC = ACCURACY


def test_variants_one_axis_at_a_time():
    block = {**ACC["scenes"]["acc"]["accuracy"]}
    labels = {(v["axis"], v["label"], v["seeds"]) for v in accuracy.variants(block)}
    assert labels == {
        ("reference", "N64_tol1e-10_steps20", 1),
        ("N", "N16_tol1e-10_steps20", 1), ("N", "N32_tol1e-10_steps20", 1),
        ("tol", "N64_tol1e-4_steps20", 1), ("n_steps", "N64_tol1e-10_steps10", 1),
        ("defaults", "N32_tol1e-8_steps20", 3),
    }


def test_perimeter_correction_reduces_the_pixel_bias():
    # The same continuous surface at N = 64, 128, 256 against N = 512: the pixel count
    # converges from above at first order in dx, and subtracting c P dx removes most of it.
    p0 = 0.004
    res = {}
    for n in (64, 128, 256, 512):
        h = generate_surface(n, 4, 16, 0.8, 0, rms_slope=0.1)
        ds = solve_contact(h, [p0], tol=1e-10)
        res[n] = (float(ds.area_fraction[0]), float(ds.contact_perimeter[0]), 1.0 / n)
    ref = res[512][0]
    ref_corr = perimeter_corrected_area(*res[512])
    raw = [abs(res[n][0] - ref) / ref for n in (64, 128, 256)]
    corr = [abs(perimeter_corrected_area(*res[n]) - ref_corr) / ref_corr for n in (64, 128, 256)]
    assert raw[0] > raw[1] > raw[2]
    # corrected, even 8 points per shortest wavelength beat the pixel count at 32
    assert max(corr) < raw[2], (raw, corr)
    c_fit = accuracy.fit_perimeter_c(*zip(*[res[n] for n in (64, 128, 256)], strict=True), ref)
    assert 0.0 < c_fit < 0.5


def test_relative_error_and_cost_table():
    assert accuracy.relative_error(1.01, 1.0) == pytest.approx(0.01)
    summary = xr.Dataset({"err_kappa": ("variant", [0.02, 0.005, 0.0005]),
                          "work_per_case": ("variant", [1.0, 3.0, 9.0])},
                         coords={"variant": ["a", "b", "c"]})
    table = accuracy.cost_table(summary, "kappa", targets=(1e-2, 1e-3, 1e-4))
    assert table == {1e-2: ("b", 3.0), 1e-3: ("c", 9.0), 1e-4: None}


@pytest.mark.slow
def test_tiny_accuracy_scene_end_to_end(accuracy_run):
    """The tiny accuracy study (the session's run, shared with test_reader)."""
    wd, out = accuracy_run.wd, accuracy_run.out
    s = xr.open_dataset(out / "accuracy" / "summary.nc")
    assert set(s["axis"].values) == {"reference", "N", "tol", "n_steps", "defaults", "seeds"}
    ref = s.sel(variant="N64_tol1e-10_steps20")
    assert float(ref["err_area"]) == 0.0 and float(ref["err_kappa"]) == 0.0
    # coarser grids are further from the reference
    e16 = float(s.sel(variant="N16_tol1e-10_steps20")["err_area"])
    e32 = float(s.sel(variant="N32_tol1e-10_steps20")["err_area"])
    assert e16 > e32 > 0
    # the work is N² x the iterations of each setting's cases (the seeds rows: of all k x 2 H surfaces)
    case = xr.open_dataset(out / "accuracy" / "N32_tol1e-10_steps20" / "kl2_ks8_H0.5_s0.nc")
    assert np.all(s["work_per_case"].values > 0) and float(s.sel(variant="N32_tol1e-10_steps20")["work_per_case"]) \
        == pytest.approx(32 ** 2 * np.mean([float(xr.open_dataset(p)["iterations"].sum()) for p in
                                            sorted((out / "accuracy" / "N32_tol1e-10_steps20").glob("*.nc"))]))
    assert int(case["iterations"].sum()) > 0
    # no timing inside: the summary made again from the same cases is the same bytes
    first = {p: (out / "accuracy" / p).read_bytes() for p in ("summary.nc", "summary.csv", "summary.md")}
    assert run_snakemake(wd, "-j1", "-R", "accuracy_summary", "--", "results/acc/accuracy/summary.nc").returncode == 0
    assert {p: (out / "accuracy" / p).read_bytes() for p in first} == first
    assert (out / "figures" / "accuracy.png").stat().st_size > 1000
    assert "err kappa" in (out / "accuracy" / "summary.md").read_text()

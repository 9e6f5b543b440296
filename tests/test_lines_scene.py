"""Line scans and generated profiles as scenes (issue 49): planning checks, and slow end-to-end runs to the report
(the session's runs of tests/conftest.py, which test_reader opens in a browser)."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from caption_check import assert_scene_captions_true
from cfcheck import assert_cf_clean
from conftest import LINESCANS, SceneRun
from roughcontact.pipeline.config import ConfigError
from roughcontact.pipeline.scenes import validate_config
from roughcontact.studies import report


def _measured(files: dict, **contact) -> dict:
    """A config with one scene ``m`` of line-scan files (paths relative to the working directory)."""
    return {"scene": "m", "scenes": {"m": {
        "topography": {"files": files, "unit": "um", "file_unit": "um", "detrend": "height"},
        "contact": {"load": {"n_steps": 12}, **contact},
        "fit": {"window": [0.02, 0.3], "n_boot": 20},
    }}}


def test_a_too_short_line_scan_is_refused_at_planning(monkeypatch):
    monkeypatch.chdir(LINESCANS)
    with pytest.raises(ConfigError, match=r"scene 'm', field 'topography.files.short': csv-2.csv: the line scan has "
                                          r"8 points; a profile needs at least 16"):
        validate_config(_measured({"short": "csv-2.csv", "scan": "nonuniform.asc"}))


def test_line_scans_and_maps_are_not_mixed(tmp_path, monkeypatch):
    np.save(tmp_path / "map.npy", np.random.default_rng(0).standard_normal((16, 16)))
    shutil.copy(LINESCANS / "nonuniform.asc", tmp_path)
    monkeypatch.chdir(tmp_path)
    cfg = _measured({"scan": "nonuniform.asc", "map": {"path": "map.npy", "physical_size": [1.0, 1.0]}})
    with pytest.raises(ConfigError, match=r"field 'topography.files': mixes line scans \(scan\) and maps \(map\); "
                                          r".* put the line scans in a scene of their own"):
        validate_config(cfg)


def test_a_line_scan_scene_refuses_clusters(monkeypatch):
    monkeypatch.chdir(LINESCANS)
    cfg = _measured({"scan": "nonuniform.asc", "xy": "xy-1.txt"}, outputs={"clusters": True})
    with pytest.raises(ConfigError, match=r"field 'contact.outputs.clusters': labels a map's contact clusters; .* "
                                          r"\(topography files scan, xy are line scans\); remove it"):
        validate_config(cfg)


def _assert_ran(run: SceneRun, tables: Path, figures=("area_load", "kappa")) -> Path:
    """Every load step of every case converged, and the report was built."""
    out = run.out
    contact = sorted((out / "contact").glob("*.nc"))
    assert contact
    for path in contact:
        with xr.open_dataset(path) as ds:
            assert ds.attrs["surface_dimension"] == 1 and "y" not in ds.dims
            assert bool(ds.converged.all()), path
    for name in figures:
        assert (out / "figures" / f"{name}.png").stat().st_size > 10_000
        assert "These cases are profiles" in (out / "figures" / f"{name}.caption.rst").read_text()
    for part in ("summary", "result"):  # the report says the paper's constants are of 2-D surfaces
        assert "These cases are profiles" in (out / "report" / f"{part}.rst").read_text()
    _assert_flags_and_numbers_true(out)
    assert_cf_clean(contact + sorted((out / "surfaces").glob("*.nc")), tables)
    return out


def _assert_flags_and_numbers_true(out: Path) -> None:
    """No constant of cel.csv is marked constrained whose interval does not hold it strictly inside (two real line
    scans gave kappa = 108.7 [7.09, 108.68] "yes", the lines scene beta = 1.87 [0.18, 1.87]), and the report prints
    no number as 0 that is not (the lines scene's "0 [0, 3100]")."""
    rows = report.read_fit_csv((out / "fit" / "cel.csv").read_text())
    for row in rows:
        if row["constrained"] == "yes":
            value, low, high = (float(row[k]) for k in ("value", "ci_low", "ci_high"))
            assert low < value < high and high - low < abs(value), row
    text = "".join((out / "report" / f"{part}.rst").read_text() for part in ("summary", "result"))
    assert not re.search(r"(?<![\d.])0(\.0+)? \[", text), text  # a fitted value is never exactly 0


@pytest.mark.slow
def test_a_measured_scene_of_line_scans_runs_to_the_report(line_scans_run, tmp_path, monkeypatch):
    """SurfaceTopography's two non-uniform line scans (134 and 132 points), resampled and solved in plane strain
    on the free boundary, every step converged, the fit and the report built."""
    wd = line_scans_run.wd
    out = _assert_ran(line_scans_run, tmp_path / "cf-tables", figures=("measured_area_load", "measured_kappa"))
    assert (out / "figures" / "topographies.png").stat().st_size > 10_000
    with xr.open_dataset(out / "surfaces" / "scan.nc") as surface:
        assert '"resampled"' in surface.attrs["source"] and surface.heights.dims == ("topography", "x")
    assert (out / "fit" / "cel.nc").exists()
    _assert_unresolved_steps_reported(out)
    monkeypatch.chdir(wd)  # the scene's paths are relative to its working directory
    assert_scene_captions_true(wd, line_scans_run.scene)


def _assert_unresolved_steps_reported(out: Path) -> None:
    """Issue 60 item 3 (the shared run's 30 load steps): xy-1.txt's first six steps hold A/A0 flat at 3 of its 132
    nodes, one patch of 3: the contact file flags them unresolved with that node count; nonuniform.asc's first 19
    have patches of 1 to 3 nodes. The load-curve figures' captions name those 25 steps with their node counts, the
    fit job's log says it left the ones in its window out."""
    with xr.open_dataset(out / "contact" / "xy.nc") as xy, xr.open_dataset(out / "contact" / "scan.nc") as scan:
        xy, scan = xy.squeeze("topography"), scan.squeeze("topography")
        assert xy.contact_nodes.values[:6].tolist() == xy.largest_patch_nodes.values[:6].tolist() == [3] * 6
        assert np.all(xy.area_fraction.values[:6] == 3 / 132)
        assert xy.contact_resolved.values.tolist() == [False] * 6 + [True] * 24
        assert scan.contact_resolved.values.tolist() == [False] * 19 + [True] * 11
        assert scan.largest_patch_nodes.values[:19].max() == 3 and scan.largest_patch_nodes.values[19:].min() >= 4
        for ds in (xy, scan):
            assert ds.contact_resolved.attrs["flag_meanings"] == "unresolved resolved"
    for name in ("measured_area_load", "measured_kappa"):
        text = (out / "figures" / f"{name}.caption.rst").read_text()
        assert "Hollow black circles: 25 load steps whose contact is unresolved: the grid does not resolve it, the " \
               "largest contact patch holding 1 to 3 nodes" in text, text
    assert "out of the fit: their contact is unresolved" in (out / "logs" / "fit_cel.log").read_text()


@pytest.mark.slow
def test_a_generated_profile_scene_runs_to_the_report(lines_run, tmp_path):
    """The `lines` scene's tiny variant (the session's run)."""
    out = _assert_ran(lines_run, tmp_path / "cf-tables")
    assert (out / "figures" / "contact_map.png").stat().st_size > 10_000  # profiles, deformed surface, pressure
    assert_scene_captions_true(lines_run.wd, lines_run.scene)

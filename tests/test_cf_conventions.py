"""Every kind of file the pipeline writes passes the CF checker (CF-1.8) with no error and no warning.

``cfchecks`` (cfchecker) checks them where it runs; it needs the system's libudunits2, which pip
cannot install, so elsewhere tests/cfcheck.py's own checks (UDUNITS-2 through cf_units) stand in
for it (its module docstring). The files here are written in-process by the functions the
workflow's scripts call (seconds); test_workflow checks the files of real runs the same way.
"""
import json
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from cfcheck import assert_cf_clean, cfchecks_command, own_checks, run_cfchecks
from roughcontact.analysis import aggregate, fit
from roughcontact.pipeline import provenance
from roughcontact.pipeline.datasets import (
    contact_dataset,
    measured_surface_dataset,
    representativity_batch,
    representativity_dataset,
    split_cases,
    surface_dataset,
)
from roughcontact.pipeline.io import read_dataset, write_dataset
from roughcontact.solver import solve_contact
from roughcontact.statistics.representativity import gaussian_l2_error
from roughcontact.studies import accuracy
from roughcontact.surfaces.synthetic import generate_surface, nonperiodic_moments, spectral_moments
from roughcontact.surfaces.topography import MeasuredSurface

#: Measured topographies, the shortest first (a width taken from the first name would cut the others)
#: and one whose name is longer in UTF-8 bytes (11) than in letters (10).
NAMES = ["frt", "frt2", "ibwspot", "Oberfläche"]
LOADS = [0.001, 0.003, 0.006]  # p0/E*: A/A0 from about 0.02 to 0.12 at rms slope 0.1
WINDOW = (0.01, 0.2)


def _write(ds, path, stage, params=None):
    return write_dataset(ds, path, stage=stage, scene="cf", scene_parameters=params or {})


def _allow_nan(ds):
    for name in ds.data_vars:
        if ds[name].dtype.kind == "f":
            ds[name].attrs["allow_nan"] = 1
    return ds


def _generated(root: Path) -> dict[str, Path]:
    """One file of each kind of a generated scene in um and MPa, as the workflow's scripts write them."""
    kw = {"k_l": "2", "k_s": "8", "hurst": "0.8"}
    out, contacts, names = {}, [], []
    for seed in (0, 1):
        h = generate_surface(32, 2.0, 8.0, 0.8, seed, rms_slope=0.1, length=1.0)
        surf = surface_dataset(h, seed=seed, length=1.0, normalisation={"rms_slope": 0.1}, length_unit="um", **kw)
        out.setdefault("surface", _write(surf, root / f"surface{seed}.nc", "surface"))
        result = solve_contact(h, LOADS, length_unit="um", pressure_unit="MPa")
        stats = spectral_moments(h, 1.0)
        case = contact_dataset(result, rms_slope=stats["rms_slope"], alpha=stats["alpha"], e_star=1.0, seed=seed, **kw)
        names.append(str(_write(case, root / f"contact{seed}.nc", "contact", {"seed": seed})))
        contacts.append(read_dataset(names[-1], stage="contact"))
    out["contact"] = Path(names[0])
    agg = aggregate.aggregate_contact(contacts, names)
    agg = agg.merge(aggregate.seed_statistics(agg))
    agg, _, varying = provenance.attach_settings(agg, contacts)
    assert varying == ["seed"]
    out["aggregate_contact"] = _write(agg, root / "aggregate_contact.nc", "aggregate")
    batch = representativity_batch({"N": 32, "L": 1.0, "plateau": False, "rms_height": 0.1, "unit": "um"},
                                   seeds=2, n_bins=20, k_l=kw["k_l"], k_s=[kw["k_s"]], hurst=kw["hurst"])
    out["representativity"] = _write(batch, root / "representativity.nc", "representativity")
    batch = read_dataset(out["representativity"], stage="representativity")
    rep = aggregate.combine_cases(split_cases(batch), ["r0", "r1"], kind="representativity")
    out["aggregate_representativity"] = _write(rep.merge(aggregate.representativity_statistics(rep)),
                                               root / "aggregate_representativity.nc", "aggregate")
    cel = fit.fit_cel(agg, n_boot=10, on_insufficient="nan", window=WINDOW, min_points=3)
    out["fit"] = _write(_allow_nan(cel), root / "fit.nc", "fit")
    setting = {"label": "N32", "value": "", "N": "32", "tol": "1e-8", "n_steps": "3", "seeds": 2}
    summary = accuracy.summarize({"N32": agg},
                                 [{**setting, "axis": "reference"}, {**setting, "axis": "defaults"}],
                                 length=1.0, kappa_at=0.05, n_boot=10, length_unit="um")
    out["accuracy"] = _write(summary, root / "accuracy.nc", "accuracy")
    return out


def _measured(root: Path) -> dict[str, Path]:
    """One file of each kind of a measured scene (topographies :data:`NAMES`, um and MPa)."""
    out, surfaces, reps, contacts = {}, [], [], []
    for k, name in enumerate(NAMES):
        h = generate_surface(32, 2.0, 8.0, 0.8, k, rms_slope=0.1, length=100.0)[:, :24]  # 32 x 24 of 100 x 75 um
        measured = MeasuredSurface(h, (100.0, 75.0), "um", {"file": f"data/{name}.x3p", "undefined_fraction": 0.0})
        surfaces.append(_write(measured_surface_dataset(measured, name=name), root / f"surface_{k}.nc", "surface"))
        rep = representativity_dataset(gaussian_l2_error(h, 20), h, n_bins=20, topography=name, length_unit="um")
        reps.append(_write(rep, root / f"rep_{k}.nc", "representativity", {"path": f"data/{name}.x3p"}))
        slope = nonperiodic_moments(h, (100.0, 75.0))["rms_slope"]
        # loaded relative to its own slope, as a measured scene does (load.relative_to: rms_slope)
        loads = [p0 * slope / 0.1 for p0 in LOADS]
        result = solve_contact(h, loads, length=(100.0, 75.0), boundary="free", length_unit="um", pressure_unit="MPa")
        case = contact_dataset(result, rms_slope=slope, alpha=4.0, e_star=1.0, topography=name)
        contacts.append(_write(case, root / f"contact_{k}.nc", "contact", {"path": f"data/{name}.x3p"}))
    out.update(surface=surfaces[-1], representativity=reps[-1], contact=contacts[-1])
    parts = [read_dataset(p, stage="representativity") for p in reps]
    rep = aggregate.combine_topographies(parts, reps, expected=NAMES, kind="representativity")
    rep, _, varying = provenance.attach_settings(rep, parts)
    assert varying == ["path"]  # a string variable along topography (setting_path)
    out["aggregate_representativity"] = _write(rep, root / "aggregate_representativity.nc", "aggregate")
    parts = [read_dataset(p, stage="contact") for p in contacts]
    agg = aggregate.add_derived(aggregate.combine_topographies(parts, contacts, expected=NAMES))
    agg, _, _ = provenance.attach_settings(agg, parts)
    out["aggregate_contact"] = _write(agg, root / "aggregate_contact.nc", "aggregate")
    cel = fit.fit_topographies(read_dataset(out["aggregate_contact"], stage="aggregate"), n_boot=10,
                               window=WINDOW, min_points=3)
    out["fit"] = _write(_allow_nan(cel), root / "fit.nc", "fit")
    return out


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    root = tmp_path_factory.mktemp("cf")
    return {"generated": _generated(root / "generated"), "measured": _measured(root / "measured")}


KINDS = ["surface", "representativity", "contact", "aggregate_contact", "aggregate_representativity", "fit"]


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_every_kind_of_file_has_no_cf_error_or_warning(outputs, tmp_path):
    assert sorted(outputs["generated"]) == sorted([*KINDS, "accuracy"]) and sorted(outputs["measured"]) == sorted(KINDS)
    assert_cf_clean([p for files in outputs.values() for p in files.values()], tmp_path / "tables")


def test_names_are_char_arrays_of_utf8_bytes_written_whole(outputs):
    widths = {"topography": max(len(n.encode()) for n in NAMES)}
    assert widths["topography"] == 11 > len("Oberfläche") > len(NAMES[0])
    for kind in ("aggregate_contact", "aggregate_representativity", "fit"):
        path = outputs["measured"][kind]
        with netCDF4.Dataset(path) as nc:
            var = nc.variables["topography"]
            assert var.dtype == "S1" and var.dimensions == ("topography", "topography_strlen"), kind
            assert var.shape == (len(NAMES), widths["topography"]) and var.getncattr("_Encoding") == "utf-8"
            along = [v for v in nc.variables.values() if "topography" in v.dimensions and v.name != "topography"]
            assert along and all("topography" in v.getncattr("coordinates").split() for v in along
                                 if v.name not in nc.dimensions), kind
            strings = [v.name for v in nc.variables.values() if v.dtype is str or v.dtype == "S1"]
        back = read_dataset(path, stage="fit" if kind == "fit" else "aggregate")
        assert [str(t) for t in back["topography"].values] == NAMES, kind
        assert back.indexes["topography"].tolist() == NAMES
        assert all(back[s].dtype.kind in "OU" for s in strings)  # read back as text, not bytes
    with netCDF4.Dataset(outputs["measured"]["fit"]) as nc:  # the fit's labels too: estimator, constant
        assert nc.variables["estimator"].dtype == "S1" and nc.variables["constant"].dtype == "S1"
    back = read_dataset(outputs["measured"]["aggregate_representativity"], stage="aggregate")
    assert [str(v) for v in back["setting_path"].values] == [json.dumps(f"data/{n}.x3p") for n in NAMES]


def test_the_same_data_give_the_same_bytes(outputs, tmp_path):
    for kind in ("aggregate_contact", "fit"):
        stage = "fit" if kind == "fit" else "aggregate"
        ds = read_dataset(outputs["measured"][kind], stage=stage)
        first = _write(ds, tmp_path / "a.nc", stage).read_bytes()
        assert _write(ds, tmp_path / "b.nc", stage).read_bytes() == first


def test_epsilon_is_a_number_with_its_reference_length(outputs):
    for scene in ("generated", "measured"):
        rep = read_dataset(outputs[scene]["aggregate_representativity"], stage="aggregate")
        for name in ["epsilon"] + (["epsilon_mean", "epsilon_sem"] if scene == "generated" else []):
            attrs = rep[name].attrs
            assert (attrs["units"], attrs["reference_length_units"], attrs["reference_length_power"]) == \
                ("1", "um", "-1/2"), (scene, name)
    surf = read_dataset(outputs["measured"]["surface"], stage="surface")
    rep = read_dataset(outputs["measured"]["representativity"], stage="representativity")
    # the number is eps of the heights in um: eps(h / 1 um)
    assert float(rep["epsilon"].squeeze()) == gaussian_l2_error(surf["heights"].values, 20)


# --------------------------------------------------------------------- the checkers themselves
def _bad_file(path: Path) -> Path:
    """A file with what cfchecker 4.1 reported in this package's files before: a vlen string variable
    (CF 2.2) and units ``um^(-1/2)`` (3.1); and a coordinate that is not monotonic (5)."""
    ds = xr.Dataset(
        {"epsilon": (("k_s",), [0.1, 0.2, 0.3], {"units": "um^(-1/2)", "long_name": "L2 error"}),
         "label": (("k_s",), np.array(["a", "bb", "ccc"], dtype=object), {"units": "1", "long_name": "a label"})},
        coords={"k_s": ("k_s", [8.0, 32.0, 16.0], {"units": "1", "long_name": "short cutoff"})},
        attrs={"Conventions": "CF-1.8"})
    ds.to_netcdf(path, engine="netcdf4", format="NETCDF4")  # xarray's default: vlen strings
    return path


def test_own_checks_find_the_errors_cfchecks_found(tmp_path):
    lines = own_checks(_bad_file(tmp_path / "bad.nc"))
    assert any(x.startswith("label: ERROR (2.2)") for x in lines), lines
    assert any(x.startswith("epsilon: ERROR (3.1)") and "um^(-1/2)" in x for x in lines), lines
    assert any(x.startswith("k_s: ERROR (5): coordinate variable not monotonic") for x in lines), lines
    assert len(lines) == 3, lines


@pytest.mark.skipif(cfchecks_command() is None, reason="cfchecks does not run here (cfchecker not installed, or no "
                    "libudunits2 for it: pip cannot install it); test_own_checks_find_the_errors_cfchecks_found "
                    "checks the stand-in")
def test_cfchecks_finds_them_too(tmp_path):
    lines = run_cfchecks([_bad_file(tmp_path / "bad.nc")], tmp_path / "tables")[tmp_path / "bad.nc"]
    assert any("(2.2)" in x and "vlen" in x for x in lines), lines
    assert any("(3.1)" in x and "um^(-1/2)" in x for x in lines), lines
    assert any("(5)" in x and "not monotonic" in x for x in lines), lines

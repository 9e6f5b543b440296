"""Job parameters are exactly a job's inputs; combined files say which case had which settings."""
import copy

import numpy as np
import pytest
import xarray as xr

from roughcontact.pipeline import params, provenance
from roughcontact.pipeline.config.schema import load_schema
from roughcontact.pipeline.io import canonical_json
from roughcontact.pipeline.scenes import validate_config

SCHEMA = load_schema()


def _demo(cfg):
    return validate_config(cfg, SCHEMA)["scenes"]["demo"]


def _edited(shipped_config, edit):
    cfg = copy.deepcopy(shipped_config)
    edit(cfg["scenes"]["demo"])
    return _demo(cfg)


PROVIDERS = {
    "surface": lambda s: params.surface(s["contact"]),
    "representativity": lambda s: params.representativity(s["representativity"]),
    "contact": lambda s: params.contact(s["contact"]),
    "fit": params.fit,
}


@pytest.mark.parametrize(
    "edit, changed",
    [
        (lambda s: s["contact"].update(seeds=5), set()),
        (lambda s: s["contact"].setdefault("solver", {}).update(tol=1e-9), {"contact"}),
        # (more steps, not fewer: the demo stores step 30's fields)
        (lambda s: s["contact"].setdefault("load", {}).update(n_steps=40), {"contact"}),
        (lambda s: s["contact"]["surface"].update(N=512), {"surface"}),
        (lambda s: s["representativity"].update(n_bins=100), {"representativity"}),
        (lambda s: s.setdefault("fit", {}).update(window=[0.02, 0.11]), {"fit"}),
        (lambda s: s.update(description="another text"), set()),
        (lambda s: s["contact"]["grid"].update(H=["0.36", "0.84", "0.5"]), set()),
    ],
)
def test_each_provider_sees_only_its_keys(shipped_config, edit, changed):
    before = _demo(shipped_config)
    after = _edited(shipped_config, edit)
    moved = {name for name, get in PROVIDERS.items() if get(before) != get(after)}
    assert moved == changed


def test_params_are_canonical(shipped_config):
    demo = _demo(shipped_config)
    got = params.contact(demo["contact"])
    assert list(got) == sorted(got) and list(got["solver"]) == sorted(got["solver"])
    assert repr(got) == repr(params.contact(copy.deepcopy(demo["contact"])))
    assert params.surface(demo["contact"]) == {"L": 1.0, "N": 256, "plateau": False, "rms_slope": 0.1, "unit": "1"}
    assert params.accuracy_case(
        {"surface": {"rms_slope": 0.1, "L": 1.0}, "p_max": 0.005},
        {"label": "x", "axis": "N", "seeds": 3, "N": "256", "tol": "1e-8", "n_steps": "30"},
    ) == {"p_max": 0.005, "setting": {"N": "256", "n_steps": "30", "tol": "1e-8"},
          "surface": {"L": 1.0, "rms_slope": 0.1}}


def test_report_summary_holds_every_result_setting_but_no_description(shipped_config):
    demo = _demo(shipped_config)
    got = params.summary(demo)
    assert list(got) == ["contact", "fit", "representativity"]
    assert got["contact"]["seeds"] == 3 and got["fit"] == params.fit(demo)
    assert "description" not in got and "keep_surfaces" not in got["contact"]
    for unchanged in (lambda s: s.update(description="another text"),
                      lambda s: s["contact"].update(keep_surfaces=False)):
        assert params.summary(_edited(shipped_config, unchanged)) == got
    assert params.summary(_edited(shipped_config, lambda s: s["contact"].update(seeds=5))) != got
    # the fit is part of the contact study: a scene without one shows no fit settings
    assert list(params.summary({k: v for k, v in demo.items() if k != "contact"})) == ["representativity"]


def test_recorded_reads_what_was_written():
    ds = xr.Dataset(attrs={"scene_parameters": canonical_json({"b": 1, "a": {"c": 2.0}})})
    assert params.recorded(ds) == {"a": {"c": 2.0}, "b": 1}
    with pytest.raises(ValueError, match="no 'scene_parameters'"):
        params.recorded(xr.Dataset())
    with pytest.raises(ValueError, match="not JSON"):
        params.recorded(xr.Dataset(attrs={"scene_parameters": "{oops"}))


def test_flatten_roundtrip():
    tree = {"solver": {"tol": 1e-8, "max_iter": 10}, "effects": {}, "fields": [1, 2]}
    flat = provenance.flatten(tree)
    assert flat == {"solver.tol": 1e-8, "solver.max_iter": 10, "effects": {}, "fields": [1, 2]}
    assert provenance.unflatten(flat) == tree


def _case(k_l, seed, settings):
    coords = {"k_l": [float(k_l)], "k_s": [32.0], "H": [0.5], "seed": [seed]}
    ds = xr.Dataset({"x": (("k_l", "k_s", "H", "seed"), np.zeros((1, 1, 1, 1)))}, coords=coords)
    ds.attrs["scene_parameters"] = canonical_json(settings)
    return ds


def test_cases_solved_differently_get_a_per_case_variable():
    base = {"solver": {"tol": 1e-8, "max_iter": 100}, "outputs": {"fields": []}}
    other = {"solver": {"tol": 1e-9, "max_iter": 100}, "outputs": {"fields": [3]}}
    cases = [_case(4, 0, base), _case(4, 1, other), _case(16, 0, base)]
    combined = xr.Dataset(coords={"k_l": [4.0, 16.0], "k_s": [32.0], "H": [0.5], "seed": [0, 1]})
    out, common, varying = provenance.attach_settings(combined, cases)
    assert common == {"solver": {"max_iter": 100}}
    assert varying == ["outputs.fields", "solver.tol"]
    tol = out["setting_solver_tol"]
    assert tol.sel(k_l=4.0, seed=0).item() == 1e-8 and tol.sel(k_l=4.0, seed=1).item() == 1e-9
    assert np.isnan(tol.sel(k_l=16.0, seed=1).item()), "no case there: NaN, never a claimed value"
    fields = out["setting_outputs_fields"]
    assert fields.sel(k_l=4.0, seed=1).item() == "[3]" and fields.sel(k_l=16.0, seed=1).item() == ""
    assert {"units", "long_name"} <= set(tol.attrs)


def test_identical_settings_add_nothing():
    same = {"solver": {"tol": 1e-8}}
    combined = xr.Dataset(coords={"k_l": [4.0], "k_s": [32.0], "H": [0.5], "seed": [0, 1]})
    out, common, varying = provenance.attach_settings(combined, [_case(4, 0, same), _case(4, 1, same)])
    assert common == same and varying == [] and not out.data_vars

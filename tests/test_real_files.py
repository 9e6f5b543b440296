"""Seven real instrument files from SurfaceTopography's test suite, whole, through every stage and the report.

The files (tests/data/surfacetopography, MIT licence: see its LICENSE.md) are one of each format a
new user brought: Bruker .di, FRT .frt (27 % undefined), Igor .ibw, Agilent .mi, Wyko .opd (640 x
480, undefined points), Mountains .sur (563 x 484, a prime side) and ISO .x3p (dx != dy). Their
case names differ in length and the shortest sorts first: once, every aggregate cut each name to
the first one's length (frt2 -> fr). Checked: the run and ``snakemake --report`` succeed, every
load step converges, every name is whole in every NetCDF, CSV, log line, figure text and the
report, and one file of every kind is CF-clean. Loads are small and few (4 steps to p0/(E* h') =
0.02) to keep CI short: about 1.5 min of 2 cores, most of it the two largest maps.
"""
import base64
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from conftest import REPO, copy_workflow, run_snakemake

# one xdist group (make test: --dist loadgroup): the module's workflow fixture then runs once, not once per
# worker (~110 s of setup on each of the two workers in the 2026-11-28 CI-like run)
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("real_files")]

DATA = REPO / "tests" / "data" / "surfacetopography"
FILES = {"di": "di-3.di", "frt2": "frt-2.frt", "ibwspot": "spot_1-1000nm.ibw", "mi": "mi-1.mi",
         "opd1": "opd-1.opd", "sur2": "sur-2.sur", "x3p2": "x3p-2.x3p"}
NAMES = sorted(FILES)
#: What a name cut to a shorter name's length would read (2 letters and up; the shortest name has 2),
#: less the format names the logs and provenance rightly hold ("format": "frt").
FORMATS = {Path(file).suffix[1:] for file in FILES.values()}
CUT = sorted({name[:k] for name in NAMES for k in range(2, len(name))} - set(NAMES) - FORMATS)
#: A cut name standing alone (not part of a longer word, a path or a file extension such as '.opd').
CUT_TOKEN = re.compile(r"(?<![\w./-])(" + "|".join(map(re.escape, CUT)) + r")(?![\w-])")
SCENE = {
    "scene": "seven",
    "scenes": {"seven": {
        "description": "Seven instrument files from SurfaceTopography's test suite, whole.",
        "topography": {"files": {name: f"st/{file}" for name, file in FILES.items()}, "unit": "um",
                       "undefined": "harmonic", "detrend": "height"},
        "representativity": {"n_bins": 50},
        "contact": {"load": {"relative_to": "rms_slope", "p_max": 0.02, "n_steps": 4},
                    "solver": {"e_star": 1.0e5, "pressure_unit": "MPa"}},
    }},
}


@pytest.fixture(scope="module")
def seven(tmp_path_factory):
    wd = copy_workflow(tmp_path_factory.mktemp("seven") / "wf")
    (wd / "st").mkdir()
    for file in FILES.values():
        (wd / "st" / file).write_bytes((DATA / file).read_bytes())
    (wd / "seven.yaml").write_text(yaml.safe_dump(SCENE, sort_keys=False))
    res = run_snakemake(wd, "-j2", "--configfile", "seven.yaml", timeout=1500)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    rep = run_snakemake(wd, "--configfile", "seven.yaml", "--report", "report.html")
    assert rep.returncode == 0, rep.stdout[-3000:] + rep.stderr[-3000:]
    return wd


def _no_cut_names(text: str, where: str) -> None:
    found = sorted({m.group(1) for m in CUT_TOKEN.finditer(text)})
    assert not found, f"{where}: names cut short: {found}"


def test_every_step_of_every_file_converges(seven):
    agg = xr.open_dataset(seven / "results" / "seven" / "aggregate" / "contact.nc")
    assert bool(agg["converged"].all()), agg["converged"].to_series()[~agg["converged"].to_series()]
    # each file loaded to p0/(E* h') = 0.02 of its own slope
    np.testing.assert_allclose(agg["pressure"].isel(step=-1) / (1e5 * agg["rms_slope"]), 0.02, rtol=1e-12)


def test_names_are_whole_in_every_netcdf(seven):
    root = seven / "results" / "seven"
    for path in sorted(root.rglob("*.nc")):
        with xr.open_dataset(path) as ds:
            names = [str(v) for v in ds["topography"].values.ravel()] if "topography" in ds.variables else []
            if path.parent.name in ("aggregate", "fit"):
                assert names == NAMES, (path, names)
            else:
                assert names == [path.stem], (path, names)
            for key, var in ds.variables.items():
                if var.dtype.kind in "USO":
                    _no_cut_names(" ".join(map(str, var.values.ravel())), f"{path}: {key}")
            _no_cut_names(" ".join(str(v) for v in ds.attrs.values()), f"{path}: global attributes")


def test_names_are_whole_in_csv_logs_and_the_report(seven):
    root = seven / "results" / "seven"
    for path in sorted([*root.rglob("*.csv"), *root.rglob("*.log"), *root.rglob("*.rst")]):
        if path.name == "figures.rst":  # the landing page's figures: PNGs in base64 and the captions checked here
            continue
        _no_cut_names(path.read_text(errors="replace"), str(path))
    fit_log = (root / "logs" / "fit_cel.log").read_text()
    assert f"topographies pooled in the fit (7): {', '.join(NAMES)}" in fit_log
    # a constant left NaN in cel.csv has its reason in the log: 4 load steps give the paper route (the
    # topography-mean curve) at most 4 of the 6 points it needs; the joint fit may or may not converge
    cel = xr.open_dataset(root / "fit" / "cel.nc")
    assert bool(cel["value"].sel(estimator="paper").isnull().all())
    assert re.search(r"WARNING no CEL fit \(paper\) at 7 topographies pooled, window \(0\.01, 0\.11\): [0-4] points "
                     r".*\(need >= 6\); widen fit\.window or add load steps \(contact\.load\.n_steps\)",
                     fit_log), fit_log
    for estimator in cel["estimator"].values:
        if bool(cel["value"].sel(estimator=estimator).isnull().any()):
            assert re.search(rf"WARNING no CEL fit \({estimator}\) at 7 topographies pooled, window \(.*\): \S",
                             fit_log)
    # the report embeds each text file (cel.csv) as base64 data beside its own scripts, whose minified code is
    # full of two-letter names: search the files; the landing page shows summary.rst (its table of topographies)
    html = (seven / "report.html").read_text(errors="replace")
    pages = {m.group(1): base64.b64decode(m.group(2)).decode("utf-8", "replace") for m in re.finditer(
        r"data:text/[\w+.-]+(?:;charset=[\w-]+)?;filename=([^;\"]+);base64,([A-Za-z0-9+/=]+)", html)}
    assert "cel.csv" in pages, sorted(pages)
    pages["summary.rst"] = (root / "report" / "summary.rst").read_text()
    for name, text in pages.items():
        _no_cut_names(text, f"report.html: {name}")
    missing = [name for name in NAMES if not re.search(rf"``{re.escape(name)}``", pages["summary.rst"])]
    assert not missing, f"the report's summary does not name {missing}"


def test_names_are_whole_in_every_figure(seven, monkeypatch):
    from roughcontact.figures.registry import FIGURES, scene_figures
    from roughcontact.pipeline.config.files import load_config_files
    from roughcontact.pipeline.scenes import validate_config

    monkeypatch.chdir(seven)
    scene = validate_config(load_config_files([Path("seven.yaml")]))["scenes"]["seven"]
    root = seven / "results" / "seven"
    for name in scene_figures(scene):
        paths = {role: [str(root / p) for p in v] if isinstance(v, list) else str(root / v)
                 for role, v in FIGURES[name].input_paths(scene).items()}
        fig = FIGURES[name].render(paths)
        texts = [t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text"))]
        _no_cut_names("\n".join(texts), f"figure {name}")
        shown = [n for n in NAMES if any(re.search(rf"(?<![\w-]){re.escape(n)}(?![\w-])", t) for t in texts)]
        assert shown == NAMES, f"figure {name} names {shown}, not every file"


def test_one_file_of_every_kind_is_cf_clean(seven, tmp_path):
    """cfchecks (where it runs, else the same checks through cf_units): no error or warning on real maps."""
    from cfcheck import assert_cf_clean

    root = seven / "results" / "seven"
    assert_cf_clean([root / "surfaces" / "sur2.nc", root / "representativity" / "x3p2.nc",
                     root / "contact" / "frt2.nc", root / "aggregate" / "contact.nc",
                     root / "aggregate" / "representativity.nc", root / "fit" / "cel.nc"], tmp_path)

"""What researchers expect of software they cite: a licence and a citation file that agree."""
import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def test_license_file_matches_pyproject():
    licence = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["license"]
    assert licence == "MIT"
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")


def test_citation_file_cites_the_software_and_the_paper():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    assert cff["version"] == project["version"] and cff["license"] == project["license"]
    paper = cff["references"][0]
    assert paper["doi"] == "10.1103/PhysRevE.86.035601" and paper["year"] == 2012
    assert [a["family-names"] for a in paper["authors"]] == ["Yastrebov", "Anciaux", "Molinari"]


def _make_n(target):
    import subprocess

    res = subprocess.run(["make", "-n", "-B", target], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    return res.stdout


def test_make_run_installs_no_test_extras_and_make_test_does():
    run = _make_n("run")
    assert "pip install --quiet -e '.[pipeline]'" in run and "[test]" not in run
    assert "-e '.[test]'" in _make_n("test")


def test_constraints_pin_every_dependency_the_tests_need():
    import re

    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        if line and not line.startswith("#"):
            name, version = line.split("==")
            pins[re.sub(r"[-_.]+", "-", name).lower()] = version
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    wanted = project["dependencies"] + extras["topography"] + extras["pipeline"] + extras["test"]
    for req in wanted:
        name = re.sub(r"[-_.]+", "-", re.split(r"[<>=\[ ]", req)[0]).lower()
        if name == "roughcontact":  # an extra naming another (test includes pipeline)
            continue
        assert name in pins, f"{name} is not pinned in constraints.txt"


def test_the_install_step_brings_what_the_report_needs():
    # `snakemake --report` imports some packages only when it runs and stops with "Python package X
    # must be installed to create reports" (pygments, once, after a plain `pip install -e .`): every
    # such X must come with the project's dependencies and its pipeline extra, or with Snakemake's.
    import importlib.metadata
    import re
    from pathlib import Path as _Path

    import snakemake.report

    needed = set()
    for path in _Path(snakemake.report.__file__).parent.rglob("*.py"):
        needed |= set(re.findall(r"Python package (\w+) must be installed", path.read_text()))
    assert "pygments" in needed  # the scan sees what Snakemake asks for
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    installed = project["dependencies"] + project["optional-dependencies"]["pipeline"]  # what `make run` installs
    brought = {re.split(r"[<>=\[ ;]", r)[0].lower() for r in installed + importlib.metadata.requires("snakemake")}
    assert needed <= brought, f"not installed by `pip install -e '.[pipeline]'`: {sorted(needed - brought)}"

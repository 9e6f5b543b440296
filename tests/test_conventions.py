"""What researchers expect of software they cite: a licence and a citation file that agree."""
import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def test_license_file_matches_pyproject():
    licence = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["license"]["text"]
    assert licence == "MIT"
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")


def test_citation_file_cites_the_software_and_the_paper():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    assert cff["version"] == project["version"] and cff["license"] == project["license"]["text"]
    paper = cff["references"][0]
    assert paper["doi"] == "10.1103/PhysRevE.86.035601" and paper["year"] == 2012
    assert [a["family-names"] for a in paper["authors"]] == ["Yastrebov", "Anciaux", "Molinari"]

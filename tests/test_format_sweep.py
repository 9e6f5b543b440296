"""benchmarks/formats/sweep.py: the shipped instrument files read, bad ones refused, a crash reported as one."""
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from conftest import load_script

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "formats" / "sweep.py"
DATA = Path(__file__).resolve().parent / "data" / "surfacetopography"


def _module():
    return load_script(SCRIPT, "format_sweep")


def test_sweep_reads_the_shipped_files_and_refuses_the_bad_ones(tmp_path, capsys):
    sweep = _module()
    for file in DATA.iterdir():
        if file.name != "LICENSE.md":
            shutil.copy(file, tmp_path / file.name)
    np.save(tmp_path / "line.npy", np.arange(32.0))  # a line scan
    (tmp_path / "noise.x3p").write_bytes(bytes(range(256)) * 4)  # not an x3p file
    rows = {name: (outcome, detail) for name, outcome, detail in sweep.sweep(tmp_path)}
    read = sorted(n for n, (o, _) in rows.items() if o == "read")
    assert read == sorted(f.name for f in DATA.iterdir() if f.name != "LICENSE.md")
    assert rows["sur-2.sur"][1] == "563 x 484, 1961 x 1686 um, 0.0 % undefined, sur"
    assert rows["line.npy"][0] == "refused" and "line scan" in rows["line.npy"][1]
    assert rows["noise.x3p"][0] == "refused" and not rows["noise.x3p"][1].startswith(str(tmp_path))

    scene_file = tmp_path / "scene.yaml"
    assert sweep.main(["--from", str(tmp_path), "--scene", str(scene_file), "--skip", "noise.x3p"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("8 read, 1 refused, 0 CRASH\n")
    files = yaml.safe_load(scene_file.read_text())["scenes"]["formats"]["topography"]["files"]
    assert sorted(files) == ["di-3", "frt-2", "mi-1", "nid-1", "opd-1", "spot-1-1000nm", "sur-2", "x3p-2"]
    assert files["frt-2"]["path"] == str(tmp_path.resolve() / "frt-2.frt")


def test_a_crash_is_reported_and_sets_the_exit_status(tmp_path, monkeypatch, capsys):
    sweep = _module()
    shutil.copy(DATA / "mi-1.mi", tmp_path / "mi-1.mi")

    def broken(path, **_):
        raise IndexError("index 3 is out of bounds")

    monkeypatch.setattr(sweep, "read_topography", broken)
    assert sweep.main(["--from", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "| mi-1.mi | CRASH | IndexError: index 3 is out of bounds (at test_format_sweep.py:" in out


def test_solve_line_reports_a_converged_solve():
    ok, line = _module().solve_one(DATA / "mi-1.mi", 0.05, steps=3)
    m = re.fullmatch(r"\| mi-1\.mi \| 256 x 256 \| 3/3 \| (\d+) \| ([\w-]+ \d(, )?)+ \| [\d.]+ \| ([\d.]+) \|", line)
    assert ok and m, line
    assert int(m[1]) > 3 and 0 < float(m[4]) < 1


def test_solve_line_with_a_hardness_ends_with_the_plastic_area():
    ok, line = _module().solve_one(DATA / "mi-1.mi", 0.05, steps=3, hardness=0.2)
    m = re.fullmatch(r"\| mi-1\.mi \| 256 x 256 \| 3/3 \| \d+ \| box 3 \| [\d.]+ \| ([\d.]+) \| ([\d.]+) \|", line)
    assert ok and m, line
    assert 0 < float(m[2]) < float(m[1]) < 1


@pytest.mark.peer
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_solve_line_with_the_peer_ends_with_its_area():
    """ContactMechanics' A/A0 at the last load (mi-1: the same node count at tol 1e-8)."""
    pytest.importorskip("ContactMechanics", reason="ContactMechanics is not installed: peer comparison skipped")
    ok, line = _module().solve_one(DATA / "mi-1.mi", 0.05, steps=3, peer=True)
    m = re.fullmatch(r"\| mi-1\.mi .* \| ([\d.]+) \| ([\d.]+) \| ([\d.e+-]+) \| \d+ \|", line)
    assert ok and m, line
    assert float(m[2]) > 0 and float(m[3]) <= 1e-3 and abs(float(m[1]) - float(m[2])) <= 1e-3 * float(m[2])

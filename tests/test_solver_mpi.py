"""The solver over MPI ranks (issue 50): ``mpiexec -n R python -m roughcontact.solver.mpi`` against the single solve.

Each check launches the command line under ``mpiexec`` (a subprocess with a time cap) on a small
problem written to a NetCDF file, and compares rank 0's contact file with
:func:`~roughcontact.solver.solve_contact` on the same heights: the same A/A0 to a node or two, the
mean gap to 1e-6 and the iterations within two per step (the distributed transforms round
differently from pyFFTW's in-place plans, as the batched solver's do: tests/test_batch.py), with
1 and 2 ranks; with 2 ranks the exact full-contact solution ``p = p0 + (E*/2) F^-1[|q| h^]`` and
Westergaard's partial contact, whose wave runs along x, across the slab boundary. An odd split
(3 ranks on 129 rows) too. The tests skip, saying why, where mpi4py or ``mpiexec`` is missing
(``pip install 'roughcontact[mpi]'``, which the ``test`` extra brings); the slab split, the named
refusals (on a one-rank stand-in communicator) and the refusal of a missing MPI run everywhere.
"""

from __future__ import annotations

import functools
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from cfcheck import assert_cf_clean
from roughcontact.solver import solve_contact
from roughcontact.statistics.patches import contact_patches
from roughcontact.surfaces.synthetic import generate_surface
from roughcontact.theory.full_contact import full_contact_load, full_contact_pressure
from test_solver_exact import westergaard_heights, westergaard_pressure

#: Wall-clock cap of one mpiexec run (a run here takes 2-10 s on 2 busy cores): catches a hang only.
CAP = 120 * float(os.environ.get("ROUGHCONTACT_TEST_TIME_SCALE", "1"))
N = 128
P_MAX = 0.005
STEPS = 8


def _mpiexec() -> str | None:
    """The ``mpiexec`` beside this Python (the mpich wheel's), else on PATH; None without mpi4py."""
    try:
        import mpi4py  # noqa: F401
    except ImportError:
        return None
    here = Path(sys.executable).parent / "mpiexec"
    return str(here) if here.exists() else shutil.which("mpiexec")


MPIEXEC = _mpiexec()
needs_mpi = pytest.mark.skipif(MPIEXEC is None, reason="mpi4py or mpiexec not installed (pip install "
                               "'roughcontact[mpi]'; the test extra brings it)")


def heights_reads(monkeypatch, name: str = "heights") -> list[int]:
    """The number of values of each read of variable ``name`` from a NetCDF file from now on, in order (filled in
    as they happen): every read of a variable's values through xarray's netCDF4 backend, lazy ones included,
    passes ``NetCDF4ArrayWrapper.__getitem__`` with the part asked for (a hyperslab) and returns it."""
    from xarray.backends.netCDF4_ import NetCDF4ArrayWrapper

    sizes: list[int] = []
    real = NetCDF4ArrayWrapper.__getitem__

    def spy(self, key):
        out = real(self, key)
        if self.variable_name == name:
            sizes.append(int(np.size(out)))
        return out

    monkeypatch.setattr(NetCDF4ArrayWrapper, "__getitem__", spy)
    return sizes


def write_surface(path: Path, h: np.ndarray) -> Path:
    xr.Dataset({"heights": (("x", "y"), h)}, attrs={"length": 1.0}).to_netcdf(path)
    return path


def run_mpi(ranks: int, *args, check=True) -> subprocess.CompletedProcess:
    cmd = [MPIEXEC, "-n", str(ranks), sys.executable, "-m", "roughcontact.solver.mpi", *map(str, args)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=CAP)
    if check:
        assert res.returncode == 0, res.stderr
    return res


def solve_mpi(tmp_path: Path, h: np.ndarray, ranks: int, p_max: float = P_MAX, steps: int = STEPS, tol=1e-8,
              fields=False) -> xr.Dataset:
    src = write_surface(tmp_path / f"surface_{ranks}.nc", h)
    out = tmp_path / f"contact_{ranks}.nc"
    run_mpi(ranks, "--surface", src, "--p-max", p_max, "--steps", steps, "--tol", tol, "--out", out,
            *(["--fields"] if fields else []))
    return xr.load_dataset(out)


@functools.cache
def _surface(k: int, n: int = N) -> np.ndarray:
    # the paper's kind of surface, and test_batch's broadband one in wide contact (the slow case)
    return generate_surface(n, *[(2, 16, 0.8, 0, 0.1), (1, 64, 0.2, 1, 0.02)][k][:4],
                            rms_slope=[0.1, 0.02][k])


def _loads(p_max=P_MAX, steps=STEPS):
    return p_max * np.arange(1, steps + 1) / steps


@needs_mpi
@pytest.mark.parametrize("ranks", [1, 2])
# the broadband case's 2-rank run is the longest here (9 s on 2 busy cores): make test only
@pytest.mark.parametrize("k", [0, pytest.param(1, marks=pytest.mark.slow)])
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_same_answers_as_the_single_solve(tmp_path, ranks, k):
    h = _surface(k)
    ds = solve_mpi(tmp_path, h, ranks)
    ref = solve_contact(h, _loads())
    assert bool(ds.converged.all()) and ds.attrs["mpi_ranks"] == ranks
    assert np.max(np.abs(ds.area_fraction.values - ref.area_fraction.values)) <= 2.0 / N**2
    np.testing.assert_allclose(ds.mean_gap.values, ref.mean_gap.values, rtol=1e-6)
    np.testing.assert_allclose(ds.contact_perimeter.values, ref.contact_perimeter.values, rtol=1e-3)
    assert np.max(np.abs(ds.iterations.values - ref.iterations.values)) <= 2
    assert np.all(ds.residual.values <= 1e-8)
    # the contact's nodes, and its largest patch joined across the slabs (to a node or two, as A/A0)
    np.testing.assert_array_equal(ds.contact_nodes.values, np.round(ds.area_fraction.values * N**2))
    assert np.max(np.abs(ds.largest_patch_nodes.values - ref.largest_patch_nodes.values)) <= 2
    # the dataset of solve_contact: the same variables, units and long names
    for name in ref.data_vars:
        for key in ("units", "long_name"):
            assert ds[name].attrs[key] == ref[name].attrs[key] or name == "wall_time", (name, key)
    assert ds.attrs["fft_backend"] == "mpi-slab" and ds.attrs["boundary"] == "periodic"


@needs_mpi
@pytest.mark.slow  # 3 ranks on 2 cores: 8 s
def test_odd_split_three_ranks_and_gathered_fields(tmp_path):
    """129 rows on 3 ranks (43 each) and 65 spectral columns (22, 22, 21); the gathered fields are the
    single solve's to the tolerance."""
    h = generate_surface(129, 2, 16, 0.8, 3, rms_slope=0.1)
    ds = solve_mpi(tmp_path, h, 3, steps=3, fields=True)
    ref = solve_contact(h, _loads(steps=3), store_fields=[3])
    assert bool(ds.converged.all())
    assert np.max(np.abs(ds.area_fraction.values - ref.area_fraction.values)) <= 2.0 / 129**2
    p, p_ref = ds.contact_pressure.values[0], ref.contact_pressure.values[0]
    assert np.abs(p - p_ref).max() <= 1e-3 * p_ref.max()
    assert (int(ds.contact_nodes[-1]), int(ds.largest_patch_nodes[-1])) == contact_patches(p > 0)
    assert abs(p.mean() - P_MAX) <= 1e-10 * P_MAX


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_full_contact_is_exact_on_two_ranks(tmp_path):
    """Past the full-contact load the pressure is ``p0 + (E*/2) F^-1[|q| h^]`` everywhere."""
    h = generate_surface(N, 2, 8, 0.8, 5, rms_slope=0.05)
    p0 = 1.5 * full_contact_load(h)
    ds = solve_mpi(tmp_path, h, 2, p_max=p0, steps=1, tol=1e-10, fields=True)
    assert bool(ds.converged.all()) and float(ds.area_fraction[0]) == 1.0
    exact = full_contact_pressure(h, p0)
    assert np.abs(ds.contact_pressure.values[0] - exact).max() <= 1e-6 * exact.max()
    # the command's file, fields included, is CF-clean (cfchecks where it runs, else tests/cfcheck.py's checks)
    assert_cf_clean([tmp_path / "contact_2.nc"], tmp_path)


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_westergaard_on_two_ranks(tmp_path):
    """The wave runs along x, the split axis: half-width to a node, pressure to 1 % of its peak, mean gap to 1e-3."""
    n, delta = 256, 0.01
    p_star = np.pi * delta
    s = 0.5
    h = westergaard_heights(n, delta)
    ds = solve_mpi(tmp_path, h, 2, p_max=s * p_star, steps=1, tol=1e-10, fields=True)
    assert bool(ds.converged.all())
    a_exact = np.arcsin(np.sqrt(s)) / np.pi
    assert abs(float(ds.area_fraction[0]) / 2 - a_exact) <= 1.0 / n
    x = np.arange(n) / n
    p_exact = westergaard_pressure(np.where(x > 0.5, x - 1, x), s * p_star, p_star)
    profile = ds.contact_pressure.values[0][:, 0]
    assert np.linalg.norm(profile - p_exact) / (p_exact.max() * np.sqrt(n)) <= 0.01
    g_exact = delta * ((1 - s) + s * np.log(s))
    assert abs(float(ds.mean_gap[0]) - g_exact) <= 1e-3 * g_exact
    # one strip of contact around x = 0, across the boundary between the last rank's rows and the first's
    strip = contact_patches(ds.contact_pressure.values[0] > 0)[1]
    assert int(ds.largest_patch_nodes[0]) == int(ds.contact_nodes[0]) == strip


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_more_ranks_than_rows_is_refused(tmp_path):
    h = generate_surface(8, 1, 2, 0.8, 0, rms_slope=0.1)[:4]  # 4 rows
    res = run_mpi(5, "--surface", write_surface(tmp_path / "s.nc", h), "--p-max", 0.01, "--out",
                  tmp_path / "c.nc", check=False)
    assert res.returncode == 2
    assert "error: ranks: 5 MPI ranks for 4 rows along x: each rank needs at least one row (run at most 4 ranks)" \
        in res.stderr
    assert res.stderr.count("error:") == 1  # rank 0 alone says it
    assert not (tmp_path / "c.nc").exists()


def test_each_rank_reads_its_rows_and_nothing_else(tmp_path, monkeypatch):
    """``read_rows`` (no MPI needed: a stand-in communicator) reads a rank's rows in one hyperslab read, the values
    bit for bit those of the whole variable loaded, its peak memory (tracemalloc: numpy's buffers) about twice its
    rows' (xarray's decoding copies them once), far below the field's 8 MiB."""
    import tracemalloc
    from types import SimpleNamespace

    from roughcontact.solver.mpi.program import read_rows

    n = 1024
    h = np.random.default_rng(0).standard_normal((n, n))
    path = tmp_path / "s.nc"
    # a leading dimension of length 1, as the pipeline's surface files have (their case)
    xr.Dataset({"heights": (("seed", "x", "y"), h[None])}, attrs={"length": 2.0}).to_netcdf(path)
    whole = xr.load_dataset(path).heights.values[0]
    reads = heights_reads(monkeypatch)
    for rank in (0, 3, 7):
        reads.clear()
        tracemalloc.start()
        try:
            rows, shape, length = read_rows(str(path), SimpleNamespace(size=8, rank=rank))
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        x0 = rank * n // 8
        assert shape == (n, n) and length == 2.0 and rows.shape == (n // 8, n)
        assert rows.tobytes() == whole[x0:x0 + n // 8].tobytes(), rank
        assert reads == [rows.size], reads
        assert peak < 3 * rows.nbytes < h.nbytes, (rank, peak)


def test_a_nan_in_a_ranks_rows_is_named_with_its_file_and_rows(tmp_path):
    from types import SimpleNamespace

    from roughcontact.solver.mpi.program import read_rows

    h = generate_surface(16, 1, 4, 0.8, 0, rms_slope=0.1)
    h[9, 3] = np.inf
    path = write_surface(tmp_path / "s.nc", h)
    assert read_rows(str(path), SimpleNamespace(size=2, rank=0))[0].shape == (8, 16)  # rows 0..7 are fine
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))}: 'heights' holds 1 NaN or infinite value\(s\) in "
                                         r"rows 8..15 \(rank 1's\); every height must be finite: remake the file"):
        read_rows(str(path), SimpleNamespace(size=2, rank=1))


#: Bad input found on one rank (the generator runs on rank 0 alone) or before the work (--out): issue 62 found
#: each printing its error and then hanging for ever on 2 ranks. Each must end every rank in seconds.
BAD_RUNS = {
    "k_s beyond Nyquist": (["--generate", 64, 2, 40, 0.8, 0, "--rms-slope", 0.1], r"k_s must be <= n/2 = 32"),
    "k_l > k_s": (["--generate", 64, 8, 2, 0.8, 0, "--rms-slope", 0.1], r"cutoffs must satisfy 0 < k_l < k_s"),
    "H 1.5": (["--generate", 64, 2, 16, 1.5, 0, "--rms-slope", 0.1], r"hurst \(H\) must be .* got 1.5"),
    "seed -1": (["--generate", 64, 2, 16, 0.8, -1, "--rms-slope", 0.1], r"seed must be an integer >= 0"),
    "seed x": (["--generate", 64, 2, 16, 0.8, "x", "--rms-slope", 0.1], r"--generate SEED: 'x' is not an integer"),
    "negative slope": (["--generate", 64, 2, 16, 0.8, 0, "--rms-slope", -0.1], r"rms_slope must be .* got -0.1"),
    "negative length": (["--generate", 64, 2, 16, 0.8, 0, "--rms-slope", 0.1, "--length", -1],
                        r"length \(L\) must be .* got -1"),
    "--out a folder": (["--generate", 64, 2, 16, 0.8, 0, "--rms-slope", 0.1, "--out", "{tmp}"],
                       r"{tmp}: is a folder; give --out's file name"),
    "--out under a file": (["--generate", 64, 2, 16, 0.8, 0, "--rms-slope", 0.1, "--out", "{tmp}/s.nc/c.nc"],
                           r"{tmp}/s.nc/c.nc: cannot be written: {tmp}/s.nc is a file, not a folder"),
}


@needs_mpi
@pytest.mark.parametrize("case", list(BAD_RUNS))
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_bad_input_ends_every_rank_at_once(tmp_path, case):
    """Status 2, one line ``error: ...`` (rank 0's), no traceback, no load step solved, nothing written; in seconds
    (``subprocess``' cap of 60 s catches the hang: a run ends in ~2 s here)."""
    (tmp_path / "s.nc").write_text("a file")
    args, message = BAD_RUNS[case]
    args = [str(a).format(tmp=tmp_path) for a in args]
    out = tmp_path / "c.nc"
    cmd = [MPIEXEC, "-n", "2", sys.executable, "-m", "roughcontact.solver.mpi", "--p-max", "0.005", "--steps", "2",
           "--out", str(out), *args]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert res.returncode == 2, res.stderr
    errors = [line for line in res.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and re.search(message.format(tmp=tmp_path), errors[0]), res.stderr
    assert "Traceback" not in res.stderr and "step 1:" not in res.stderr
    assert not out.exists()


#: A check that fails on one rank alone, outside any collective check: main must abort the run, not return while
#: the other rank waits.
ONE_RANK_FAILS = """
import sys
import roughcontact.solver.mpi.__main__ as cli

def heights(args, comm):
    if comm.rank == 1:
        raise ValueError("rank 1 alone refuses")
    comm.barrier()  # rank 0 would wait here for ever

cli._heights = heights
sys.exit(cli.main(["--generate", "64", "2", "16", "0.8", "0", "--rms-slope", "0.1", "--p-max", "0.005",
                   "--out", sys.argv[1]]))
"""


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_an_error_on_one_rank_aborts_the_run(tmp_path):
    script = tmp_path / "one_rank_fails.py"
    script.write_text(ONE_RANK_FAILS)
    res = subprocess.run([MPIEXEC, "-n", "2", sys.executable, str(script), str(tmp_path / "c.nc")],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 2, res.stderr
    assert "error: rank 1 alone refuses" in res.stderr and "Traceback" not in res.stderr


NO_SHARED_MEMORY = """
import sys
import mpi4py
from mpi4py import MPI as real

class FailingWin:  # the machine's shared memory refused after the room check passed (another job took it)
    @staticmethod
    def Allocate_shared(*args, **kwargs):
        raise real.Exception(real.ERR_NO_MEM)

class Proxy:
    def __getattr__(self, name):
        return FailingWin if name == "Win" else getattr(real, name)

mpi4py.MPI = Proxy()  # what ``from mpi4py import MPI`` gives the slab transforms from here on
import roughcontact.solver.mpi.__main__ as cli
sys.exit(cli.main(["--generate", "64", "2", "16", "0.8", "0", "--rms-slope", "0.1", "--p-max", "0.005",
                   "--out", sys.argv[1]]))
"""


@needs_mpi
@pytest.mark.slow  # a 2-rank run (~4 s on 2 busy cores)
def test_a_shared_memory_window_refused_is_one_line(tmp_path):
    """MPI refusing the shared-memory window for the spectra (after the room check passed) ends every rank with one
    line naming the shared-memory folder, what it needed and the remedy: no traceback from inside mpi4py, no rank
    waiting for ever, no file. Both precisions' windows are made with the solver, so a refusal cannot come later, in
    the middle of a solve."""
    script = tmp_path / "no_shared_memory.py"
    script.write_text(NO_SHARED_MEMORY)
    res = subprocess.run([MPIEXEC, "-n", "2", sys.executable, str(script), str(tmp_path / "c.nc")],
                         capture_output=True, text=True, timeout=CAP)
    assert res.returncode == 2, res.stderr
    assert re.search(r"error: ranks: the shared memory for this machine's 2 ranks' spectra \([\d.]+ MiB in /dev/shm\) "
                     r"could not be had \(.+\); free room there \(df /dev/shm\), or give a container more "
                     r"\(docker run --shm-size\)", res.stderr), res.stderr
    assert "Traceback" not in res.stderr and res.stderr.count("error:") == 1 and not (tmp_path / "c.nc").exists()


def test_generator_values_name_the_value_at_fault():
    from roughcontact.solver.mpi.__main__ import generator_values

    assert generator_values(["64", "2", "16", "0.8", "3"]) == (64, 2.0, 16.0, 0.8, 3)
    with pytest.raises(ValueError, match=r"--generate N: '6.5' is not an integer"):
        generator_values(["6.5", "2", "16", "0.8", "3"])
    with pytest.raises(ValueError, match=r"--generate H: 'high' is not a number"):
        generator_values(["64", "2", "16", "high", "3"])


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_explicit_loads_and_a_rectangular_cell(tmp_path):
    """``--loads`` (the pipeline's resolved schedule, exact) and ``--length Lx --length-y Ly``: the single solve's
    answers on the same rectangle; ``--length-y`` alone is refused in one line."""
    h = _surface(0)
    src = write_surface(tmp_path / "s.nc", h)
    loads = [0.001, 0.0025, 0.004]
    run_mpi(2, "--surface", src, "--loads", *map(repr, loads), "--length", 2.0, "--length-y", 1.5,
            "--length-unit", "um", "--pressure-unit", "MPa", "--out", tmp_path / "c.nc")
    ds = xr.load_dataset(tmp_path / "c.nc")
    ref = solve_contact(h, loads, length=(2.0, 1.5), length_unit="um", pressure_unit="MPa")
    assert ds.pressure.values.tolist() == loads and ds.attrs["length_y"] == ref.attrs["length_y"] == 1.5
    assert np.max(np.abs(ds.area_fraction.values - ref.area_fraction.values)) <= 2.0 / N**2
    np.testing.assert_allclose(ds.mean_gap.values, ref.mean_gap.values, rtol=1e-6)
    assert ds.mean_gap.attrs["units"] == ref.mean_gap.attrs["units"] == "um"
    res = run_mpi(1, "--surface", src, "--loads", 0.001, "--length-y", 1.5, "--out", tmp_path / "d.nc", check=False)
    assert res.returncode == 2 and "error: --length-y needs --length (the side along x)" in res.stderr


class OneRank:
    """A communicator of one rank without MPI: all that the checks before a solve call (``allgather``).

    The refusals run in the test process itself, which then never initialises MPI (an MPI library
    loaded in a pytest worker would stay there for the worker's later tests).
    """

    size, rank = 1, 0

    def allgather(self, value):
        return [value]


def test_what_the_mpi_solver_refuses():
    """Named refusals, checked before any transform (runs without mpi4py too)."""
    from roughcontact.solver import PlasticityCap
    from roughcontact.solver.mpi import solve_contact_mpi

    h = _surface(0)
    comm = OneRank()
    with pytest.raises(ValueError, match="periodic half-space only, got boundary='free': the free boundary's"):
        solve_contact_mpi(h, h.shape, [0.001], comm=comm, boundary="free")
    with pytest.raises(ValueError, match=r"not the effects \(PlasticityCap\)"):
        solve_contact_mpi(h, h.shape, [0.001], comm=comm, effects=(PlasticityCap(0.5),))
    with pytest.raises(ValueError, match="elastic method 'pk-fourier-f32' only, got 'pk'"):
        solve_contact_mpi(h, h.shape, [0.001], comm=comm, method="pk")
    with pytest.raises(ValueError, match="surface is flat"):
        solve_contact_mpi(np.ones_like(h), h.shape, [0.001], comm=comm)
    with pytest.raises(ValueError, match=r"rows 0..127\) must contain only finite"):
        solve_contact_mpi(np.where(h > 0, np.nan, h), h.shape, [0.001], comm=comm)
    with pytest.raises(ValueError, match=r"holds rows 0..255 of the grid \(256, 256\), shape \(256, 256\); got "
                                         r"\(128, 128\)"):
        solve_contact_mpi(h, (256, 256), [0.001], comm=comm)


#: Ways a Python can lack MPI: no mpi4py at all; mpi4py's wheel without an MPI library, whose ``from mpi4py
#: import MPI`` raises ``RuntimeError: cannot load MPI library`` (mpi4py 4.1, checked in a venv without mpich).
NO_MPI = {
    "no mpi4py": "sys.modules['mpi4py'] = None",
    "no MPI library": ("import types; m = types.ModuleType('mpi4py'); m.__path__ = []; "
                       "m.__getattr__ = lambda name: (_ for _ in ()).throw(RuntimeError('cannot load MPI library')); "
                       "sys.modules['mpi4py'] = m"),
}


@pytest.mark.parametrize("how", list(NO_MPI))
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_mpi_requested_but_not_installed(tmp_path, how):
    """Without MPI the command says how to install it, in one line, exit status 2 (runs everywhere)."""
    code = (f"import sys; {NO_MPI[how]}; from roughcontact.solver.mpi.__main__ import main; "
            f"sys.exit(main(['--generate', '64', '2', '16', '0.8', '0', '--rms-slope', '0.1', '--p-max', '0.001', "
            f"'--out', {str(tmp_path / 'c.nc')!r}]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=CAP)
    assert res.returncode == 2, res.stderr
    assert res.stderr.startswith("error: the MPI solver needs mpi4py and an MPI runtime, not importable here")
    assert "pip install 'roughcontact[mpi]'" in res.stderr and res.stderr.count("\n") == 1


def test_slabs_split_rows_and_spectral_columns():
    """The decomposition alone (no MPI): consecutive blocks, the first ones a row or column larger; refusals."""
    from roughcontact.solver.mpi import Slabs

    parts = [Slabs((129, 128), 3, r) for r in range(3)]
    assert [p.rows[p.rank] for p in parts] == [(0, 43), (43, 86), (86, 129)]
    assert [(p.c0, p.c1) for p in parts] == [(0, 22), (22, 44), (44, 65)]
    assert parts[2].local_shape == (43, 128) and parts[2].spectrum_shape == (129, 21)
    with pytest.raises(ValueError, match=r"ranks: 5 MPI ranks for 4 rows along x"):
        Slabs((4, 16), 5, 0)
    with pytest.raises(ValueError, match=r"ranks: 4 MPI ranks for 3 columns of the half spectrum \(ny = 4\)"):
        Slabs((8, 4), 4, 0)


@pytest.mark.parametrize("dtype", [np.complex64, np.complex128])
def test_the_slab_transpose_copies_strided_blocks_value_for_value(dtype):
    """``copy_transposed`` (tiles) gives numpy's transpose bit for bit, on strided blocks of any shape and B."""
    from roughcontact.solver.mpi.transpose import copy_transposed

    rng = np.random.default_rng(3)
    src = (rng.standard_normal((2, 70, 101)) + 1j * rng.standard_normal((2, 70, 101))).astype(dtype)
    dst = np.zeros((2, 90, 150), dtype)
    for tile in (1, 7, 32):  # smaller and larger than the blocks' sides, and not dividing them
        dst[...] = 0
        copy_transposed(dst[:, 5:88, 10:80], src[:, :, 9:92], tile)
        assert np.array_equal(dst[:, 5:88, 10:80], src[:, :, 9:92].transpose(0, 2, 1))
        assert not dst[:, :5].any() and not dst[:, 88:].any() and not dst[:, :, :10].any() and not dst[:, :, 80:].any()


@pytest.mark.parametrize(("shape", "ranks"), [((1024, 1024), 2), ((4096, 2048), 2), ((2048, 2048), 4),
                                              ((256, 256), 64)])
def test_the_shipped_wisdom_holds_every_slab_transform(shape, ranks):
    """Each rank's slab transforms (both precisions) are planned from the shipped wisdom alone: none adds an entry.

    FFTW's estimating planner alone cost 1.5-1.6x the measured plans' time at 1024^2-4096^2 on 2 ranks
    (benchmarks/README.md, "The slab transforms' plans and transposes"); a wisdom entry FFTW cannot apply would make
    it forget the whole store and plan by those heuristics, which this catches too.
    """
    pyfftw = pytest.importorskip("pyfftw")
    from roughcontact.core import fft
    from roughcontact.solver.mpi import slabs

    # the file's default set, which every processor model but the AMD EPYC plans with (that set has no slab
    # plans: its model plans them by FFTW's heuristics), whatever the processor this test runs on
    data = json.loads(fft.WISDOM_FILE.read_text())
    default = data["machines"][data["default"]]
    record = default["slabs"]
    assert record["sizes"] == list(slabs.WISDOM_SIZES) and record["ranks"] == list(slabs.WISDOM_RANKS)
    shipped = tuple(default[k].encode("ascii") for k in ("double", "single", "long_double"))
    for rank in sorted({0, ranks - 1}):
        for real in (np.float32, np.float64):
            pyfftw.forget_wisdom()
            pyfftw.import_wisdom(shipped)
            before = pyfftw.export_wisdom()
            slabs.SlabPlans(slabs.Slabs(shape, ranks, rank), 1, real, 1, flags=fft.PLANNER_FLAGS)
            assert pyfftw.export_wisdom() == before, (shape, ranks, rank, real)
    pyfftw.forget_wisdom()


#: A 2-rank solve whose float32 iteration stalls at once (its stall window set to 0), so that every step
#: goes on with the float64 fallback over the ranks; rank 0 prints the per-step columns as JSON.
_STALLED_RUN = """
import json, sys
import numpy as np
from mpi4py import MPI
import roughcontact.solver.iteration as bi
from roughcontact.solver.mpi import rows_of, solve_contact_mpi
bi.STALL_WINDOW = 0
h = np.load(sys.argv[1])
x0, x1 = rows_of(h.shape, MPI.COMM_WORLD)
ds = solve_contact_mpi(np.ascontiguousarray(h[x0:x1]), h.shape, json.loads(sys.argv[2]))
if MPI.COMM_WORLD.rank == 0:
    print(json.dumps({k: ds[k].values.tolist() for k in ("area_fraction", "mean_gap", "converged", "solver_path",
                                                         "residual")}))
"""


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_a_stalled_step_goes_on_in_float64_over_the_ranks(tmp_path):
    """The single solve's first fallback over 2 ranks: the iteration with float64 products (``pk-fourier``)
    from where the float32 one stalled, converging to the single solve's answer."""
    import json

    from roughcontact.solver.workspace import SOLVER_PATHS

    h = _surface(0)
    np.save(tmp_path / "h.npy", h)
    loads = _loads()[:3].tolist()
    res = subprocess.run([MPIEXEC, "-n", "2", sys.executable, "-c", _STALLED_RUN, str(tmp_path / "h.npy"),
                          json.dumps(loads)], capture_output=True, text=True, timeout=CAP)
    assert res.returncode == 0, res.stderr
    got = json.loads(res.stdout.strip().splitlines()[-1])
    ref = solve_contact(h, loads)
    assert all(got["converged"]) and max(got["residual"]) <= 1e-8
    assert set(got["solver_path"]) == {SOLVER_PATHS.index("pk-fourier")}
    assert np.max(np.abs(np.array(got["area_fraction"]) - ref.area_fraction.values)) <= 2.0 / N**2
    np.testing.assert_allclose(got["mean_gap"], ref.mean_gap.values, rtol=1e-6)


#: Each rank transforms its rows of a field (odd split, B = 2, both precisions) with the transposes through a shared
#: window on all ranks, on two machines' worth of ranks (a node split in two: shared within, MPI across), through
#: MPI alone (nodes of one rank) and where the machine has no room to share (MPI alone); each rank checks that all
#: give the same bits and numpy's rfft2 to rounding, and that closing frees the exchanges' MPI datatypes.
_TRANSFORMS = """
import sys
import numpy as np
from mpi4py import MPI
from roughcontact.solver.mpi import slabs as slabs_module
from roughcontact.solver.mpi.slabs import FftwSlabFFT, Slabs
comm = MPI.COMM_WORLD
shape = (37, 30)
slabs = Slabs(shape, comm.size, comm.rank)
rng = np.random.default_rng(5)
whole = rng.standard_normal((2, *shape))
nodes = {"shared": None, "two machines": comm.Split(comm.rank * 2 // comm.size, comm.rank),
         "mpi only": comm.Split(comm.rank, 0), "no room": None}
out = {}
for name, node in nodes.items():
    if name == "no room":  # the machine's shared-memory file system too small for the spectra: each keeps its own
        slabs_module.fits_shared_memory = lambda nbytes, path=None: False
    fft = FftwSlabFFT(comm, slabs, node=node)
    res = []
    for real in (np.float32, np.float64):
        x = whole[:, slabs.x0:slabs.x1].astype(real)
        spec = fft.forward(x).copy()
        res += [spec, fft.backward(spec.copy()).copy()]
    types = [t for r in (np.float32, np.float64) for ts in getattr(fft.plans(2, r), "types", {}).values() for t in ts]
    assert bool(types) == (name in ("mpi only", "no room") or (name == "two machines" and comm.size >= 2)), name
    fft.close()
    assert all(t == MPI.DATATYPE_NULL for t in types), name  # the exchanges' datatypes freed
    out[name] = res
    shares = name == "shared" or (name == "two machines" and comm.size >= 4)  # 2 ranks: a machine each
    assert (fft.node is not None) == shares and len(fft.local) == (comm.size // 2 if name != "shared" and shares
                                                                   else comm.size if shares else 1), name
ref = np.fft.rfft2(whole)[:, :, slabs.c0:slabs.c1].transpose(0, 2, 1)
for name, (s32, b32, s64, b64) in out.items():
    for spec, back, tol in ((s32, b32, 1e-5), (s64, b64, 1e-12)):
        assert np.abs(spec - ref).max() < tol * np.abs(ref).max(), name
        assert np.abs(back / (shape[0] * shape[1]) - whole[:, slabs.x0:slabs.x1]).max() < tol * 10, name
    for a, b in zip(out["shared"], out[name]):
        assert np.array_equal(a, b), name
done = comm.gather(comm.rank)  # every rank's checks passed (a failed one exits non-zero)
if comm.rank == 0:
    print("ok", *done, flush=True)
"""


@needs_mpi
@pytest.mark.parametrize("ranks", [2, 4])
def test_the_transposes_through_shared_memory_and_mpi_give_the_same_bits(tmp_path, ranks):
    """The distributed transforms with each rank's blocks copied into the shared window of its machine's ranks, on a
    machine split in two (shared within each half, ``Alltoallw`` across), through ``Alltoallw`` alone and where
    ``/dev/shm`` has no room (``Alltoallw`` alone): the same bits, and numpy's ``rfft2`` (float32 to 1e-5, float64
    to 1e-12 of the largest value; the inverse likewise)."""
    script = tmp_path / "transforms.py"
    script.write_text(_TRANSFORMS)
    res = subprocess.run([MPIEXEC, "-n", str(ranks), sys.executable, str(script)], capture_output=True, text=True,
                         timeout=CAP)
    assert res.returncode == 0, res.stderr
    assert res.stdout.split() == ["ok", *map(str, range(ranks))]


def test_shared_memory_is_used_only_where_it_has_room(tmp_path):
    """``fits_shared_memory``: a file system's free space against the bytes asked; True where the folder is missing
    (the MPI library's own shared memory, whatever it is)."""
    from roughcontact.solver.mpi.slabs import fits_shared_memory

    assert fits_shared_memory(1, tmp_path)
    assert not fits_shared_memory(2**70, tmp_path)
    assert fits_shared_memory(2**70, tmp_path / "missing")

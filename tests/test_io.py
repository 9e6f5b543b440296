"""NetCDF at the edges: labels enforced, atomic and deterministic writes, bad files named.

Every output (NetCDF, CSV/Markdown, figures) is written atomically with the mode the
umask gives; interrupted writes leave the previous file (or none) plus a temporary.
"""
import os
import signal
import stat
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure

from roughcontact import generate_surface
from roughcontact.core.files import atomic_output, current_umask, write_text_atomic
from roughcontact.figures.style import save_figure
from roughcontact.pipeline.datasets import surface_dataset
from roughcontact.pipeline.io import InputFileError, config_hash, read_dataset, write_dataset

PARAMS = {"surface": {"N": 16}, "seeds": 1}


def _surface_ds():
    h = generate_surface(16, 1, 4, 0.5, 0, rms_slope=0.1)
    return surface_dataset(h, k_l="1", k_s="4", hurst="0.5", seed=0, length=1.0, normalisation={"rms_slope": 0.1})


def _write(path):
    return write_dataset(_surface_ds(), path, stage="surface", scene="t", scene_parameters=PARAMS)


def test_roundtrip_and_provenance(tmp_path):
    p = _write(tmp_path / "s.nc")
    ds = read_dataset(p, stage="surface", variables=["heights"])
    assert ds.attrs["config_hash"] == config_hash(PARAMS)
    assert ds.attrs["roughcontact_stage"] == "surface" and ds.attrs["scene"] == "t"
    assert '"N":16' in ds.attrs["scene_parameters"]
    assert ds.heights.shape == (1, 1, 1, 1, 16, 16)


def test_byte_identical_rewrites(tmp_path):
    a, b = _write(tmp_path / "a.nc"), _write(tmp_path / "b.nc")
    assert a.read_bytes() == b.read_bytes()


def test_unlabelled_or_nan_variables_refused(tmp_path):
    ds = _surface_ds()
    ds["extra"] = xr.DataArray(1.0)
    with pytest.raises(ValueError, match="extra"):
        write_dataset(ds, tmp_path / "x.nc", stage="surface", scene="t", scene_parameters=PARAMS)
    ds = _surface_ds()
    ds["rms_slope"] = ds["rms_slope"] * np.nan
    with pytest.raises(ValueError, match="NaN"):
        write_dataset(ds, tmp_path / "x.nc", stage="surface", scene="t", scene_parameters=PARAMS)
    assert not list(tmp_path.iterdir()), "a refused write leaves nothing behind"


def test_failed_write_leaves_no_file(tmp_path, monkeypatch):
    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", boom)
    with pytest.raises(OSError):
        _write(tmp_path / "s.nc")
    assert not list(tmp_path.iterdir())


def test_truncated_file_named(tmp_path):
    p = _write(tmp_path / "s.nc")
    data = p.read_bytes()
    p.write_bytes(data[: len(data) // 3])
    with pytest.raises(InputFileError, match=r"s\.nc: not a readable NetCDF"):
        read_dataset(p, stage="surface")


def test_foreign_and_wrong_stage_files_named(tmp_path):
    foreign = tmp_path / "f.nc"
    xr.Dataset({"a": ("x", [1.0, 2.0])}).to_netcdf(foreign)
    with pytest.raises(InputFileError, match=r"f\.nc: not written by roughcontact"):
        read_dataset(foreign, stage="surface")
    p = _write(tmp_path / "s.nc")
    with pytest.raises(InputFileError, match="holds stage 'surface', expected 'contact'"):
        read_dataset(p, stage="contact")
    with pytest.raises(InputFileError, match="lacks required variable"):
        read_dataset(p, stage="surface", variables=["pressure"])
    with pytest.raises(InputFileError, match="does not exist"):
        read_dataset(tmp_path / "none.nc", stage="surface")
    text = tmp_path / "t.nc"
    text.write_text("hello")
    with pytest.raises(InputFileError, match="not a readable NetCDF"):
        read_dataset(text, stage="surface")
    assert os.path.exists(p)


# ------------------------------------------------------------------ atomic outputs
TIMEOUT_S = 600  # generous waits for subprocesses: only a hung child reaches them


def _figure(slope=1.0):
    fig = Figure(figsize=(2, 1.5))
    fig.add_subplot().plot([0, 1, 2], [0, slope, 2 * slope])
    return fig


def _temporaries(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def _mode(path):
    return stat.S_IMODE(path.stat().st_mode)


@pytest.fixture(params=[0o022, 0o077, 0o002], ids=lambda m: f"umask{m:03o}")
def umask(request):
    old = os.umask(request.param)
    try:
        yield request.param
    finally:
        os.umask(old)


def test_current_umask_reads_without_changing(umask):
    assert current_umask() == umask
    assert current_umask() == umask


def test_outputs_get_the_umask_mode(tmp_path, umask):
    want = 0o666 & ~umask
    # An earlier version's 0600 file (mkstemp) is replaced by one with the umask's mode.
    old = tmp_path / "s.nc"
    old.write_bytes(b"old")
    old.chmod(0o600)
    written = {
        "NetCDF": _write(old),
        "CSV": write_text_atomic(tmp_path / "fit" / "cel.csv", "a,b\n1,2\n"),
    }
    png, pdf = save_figure(_figure(), tmp_path / "fig" / "f")
    written.update({"PNG": png, "PDF": pdf})
    with atomic_output(tmp_path / "t.md") as tmp:
        tmp.write_text("# t\n")
    written["Markdown"] = tmp_path / "t.md"
    modes = {kind: oct(_mode(path)) for kind, path in written.items()}
    assert modes == {kind: oct(want) for kind in written}, f"umask {umask:03o}: modes {modes}, want {oct(want)}"
    assert not _temporaries(tmp_path) and not any(_temporaries(d) for d in tmp_path.iterdir() if d.is_dir())


def test_atomic_output_mode_even_if_writer_recreates_file(tmp_path, umask):
    target = tmp_path / "x.csv"
    with atomic_output(target) as tmp:
        tmp.unlink()
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT, 0o600)  # mkstemp-like writer
        os.write(fd, b"x\n")
        os.close(fd)
    assert _mode(target) == 0o666 & ~umask
    assert target.read_bytes() == b"x\n"


def test_atomic_output_error_keeps_previous_and_cleans_up(tmp_path):
    target = write_text_atomic(tmp_path / "a" / "x.csv", "old\n")
    with pytest.raises(RuntimeError, match="writer failed"):
        with atomic_output(target) as tmp:
            tmp.write_text("partial")
            raise RuntimeError("writer failed")
    assert target.read_text() == "old\n"
    assert _temporaries(target.parent) == []


def test_stale_temporaries_of_the_target_only_are_removed(tmp_path):
    mine = [tmp_path / ".x.csv.abc123.tmp", tmp_path / ".x.csv.k2j_9zq1.tmp"]
    others = [tmp_path / ".x.csv.bak.abc123.tmp", tmp_path / ".y.csv.abc123.tmp", tmp_path / "x.csv.tmp"]
    for p in mine + others:
        p.write_text("stale")
    write_text_atomic(tmp_path / "x.csv", "new\n")
    assert not any(p.exists() for p in mine), "stale temporaries of x.csv were left"
    assert all(p.exists() for p in others), "temporaries of other targets were removed"
    assert (tmp_path / "x.csv").read_text() == "new\n"


def test_write_dataset_uses_the_helper(tmp_path):
    # A killed NetCDF write left its temporary: the next write removes it and leaves none.
    stale = tmp_path / ".s.nc.q1w2e3r4.tmp"
    stale.write_bytes(b"\x89HDF\r\n")
    _write(tmp_path / "s.nc")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.nc"]


# An interrupted writer: the child prints READY once it is inside the write (the
# temporary holds part of the bytes) and then sleeps until killed.
CSV_CHILD = textwrap.dedent(
    """
    import sys, time
    from roughcontact.core.files import atomic_output
    with atomic_output(sys.argv[1]) as tmp:
        with open(tmp, "w") as fh:
            fh.write("kappa,mu,beta\\n1.1,0.5,")
            fh.flush()
            print("READY", flush=True)
            time.sleep(600)
    """
)

FIGURE_CHILD = textwrap.dedent(
    """
    import io, sys, time
    from matplotlib.figure import Figure
    from roughcontact.figures.style import save_figure

    target, kill_format = sys.argv[1], sys.argv[2]
    real_savefig = Figure.savefig

    def slow_savefig(self, fname, **kwargs):
        if kwargs.get("format") != kill_format:
            return real_savefig(self, fname, **kwargs)
        buf = io.BytesIO()
        real_savefig(self, buf, **kwargs)
        with open(fname, "wb") as fh:
            fh.write(buf.getvalue()[:54])  # part of the file, as left by a SIGKILL
            fh.flush()
            print("READY", flush=True)
            time.sleep(600)

    Figure.savefig = slow_savefig
    fig = Figure(figsize=(2, 1.5))
    fig.add_subplot().plot([0, 1, 2], [0, 2.0, 4.0])
    save_figure(fig, target)
    """
)


def _kill_while_writing(args):
    """Run a child until it says READY (mid-write), SIGKILL it, return its stderr."""
    proc = subprocess.Popen([sys.executable, "-c", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    guard = threading.Timer(TIMEOUT_S, proc.kill)  # a child that never gets READY
    guard.start()
    try:
        line = proc.stdout.readline()
    finally:
        guard.cancel()
    if line.strip() != "READY":
        proc.kill()
        _, err = proc.communicate(timeout=TIMEOUT_S)
        pytest.fail(f"child did not reach the middle of its write (said {line!r}, exit {proc.returncode}):\n{err}")
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate(timeout=TIMEOUT_S)
    assert proc.returncode == -signal.SIGKILL, f"child ended with {proc.returncode}, not by SIGKILL"


@pytest.mark.parametrize("previous", [True, False], ids=["over-previous", "new-file"])
def test_sigkill_mid_csv_write(tmp_path, previous):
    target = tmp_path / "fit" / "cel.csv"
    complete = "kappa,mu,beta\n1.0,0.4,0.9\n"
    if previous:
        write_text_atomic(target, complete)
    _kill_while_writing([CSV_CHILD, str(target)])
    if previous:
        assert target.read_text() == complete, "the killed write changed the previous complete file"
    else:
        assert not target.exists(), f"the killed write left a target holding {target.read_bytes()!r}"
    left = _temporaries(target.parent)
    assert len(left) == 1 and left[0].startswith(".cel.csv."), f"expected one temporary, found {left}"
    others = sorted(p.name for p in target.parent.iterdir() if p.name not in left)
    assert others == (["cel.csv"] if previous else []), f"unexpected files {others}"
    # Recovery: the rerun of the job writes the complete file and removes the stale temporary.
    write_text_atomic(target, "kappa,mu,beta\n1.1,0.5,0.8\n")
    assert target.read_text() == "kappa,mu,beta\n1.1,0.5,0.8\n"
    assert sorted(p.name for p in target.parent.iterdir()) == ["cel.csv"]


@pytest.mark.parametrize("kill_format", ["png", "pdf"])
@pytest.mark.parametrize("previous", [True, False], ids=["over-previous", "new-file"])
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_sigkill_mid_figure_write(tmp_path, kill_format, previous):
    folder = tmp_path / "figures"
    base = folder / "fig2"
    if previous:
        save_figure(_figure(slope=1.0), base)
        before = {p.name: p.read_bytes() for p in folder.iterdir()}
    _kill_while_writing([FIGURE_CHILD, str(base), kill_format])
    left = _temporaries(folder)
    assert len(left) == 1 and left[0].startswith(f".fig2.{kill_format}."), f"expected one temporary, found {left}"
    killed = folder / f"fig2.{kill_format}"
    if previous:
        assert killed.read_bytes() == before[killed.name], f"the killed write changed the previous {killed.name}"
    else:
        assert not killed.exists(), f"the killed write left {killed.name} ({killed.stat().st_size} bytes)"
    png = folder / "fig2.png"
    if kill_format == "pdf":  # the PNG was finished before the kill: complete, new
        assert png.read_bytes().endswith(b"IEND\xaeB`\x82"), "the PNG written before the kill is incomplete"
    # Recovery: the rerun leaves complete files identical to a clean save, no temporary.
    recovered = save_figure(_figure(slope=2.0), base)
    clean = save_figure(_figure(slope=2.0), tmp_path / "clean" / "fig2")
    for got, want in zip(recovered, clean, strict=True):
        assert got.read_bytes() == want.read_bytes(), f"recovered {got.name} differs from a clean save"
    assert sorted(p.name for p in folder.iterdir()) == ["fig2.pdf", "fig2.png"]


def test_full_disk_is_one_line_naming_the_file_and_leaves_nothing(tmp_path, monkeypatch):
    """ENOSPC half-way through a write: one message naming the target, no partial file, old file kept."""
    import errno
    import logging

    from roughcontact.core.files import OutputFileError, write_text_atomic
    from roughcontact.pipeline.io import run_logged, write_dataset

    target = tmp_path / "out" / "case.nc"
    write_text_atomic(target, "previous complete content")

    def full_disk(self, tmp, **kwargs):
        with open(tmp, "wb") as fh:
            fh.write(b"CDF\x01 half")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", full_disk)
    ds = xr.Dataset({"a": ("x", [1.0], {"units": "1", "long_name": "a"})},
                    coords={"x": ("x", [0], {"units": "1", "long_name": "x"})})
    with pytest.raises(OutputFileError, match=r"case\.nc: could not be written \(\[Errno 28\] No space left"):
        write_dataset(ds, target, stage="surface", scene="s", scene_parameters={})
    assert target.read_text() == "previous complete content"
    assert sorted(p.name for p in target.parent.iterdir()) == ["case.nc"]

    log = tmp_path / "job.log"
    with pytest.raises(SystemExit) as info:
        run_logged(log, lambda logger: write_dataset(ds, target, stage="surface", scene="s", scene_parameters={}))
    assert info.value.code == 1
    lines = log.read_text().splitlines()
    assert len(lines) == 1 and "ERROR" in lines[0] and "case.nc: could not be written" in lines[0], lines
    logging.getLogger("roughcontact").handlers.clear()


def test_directory_in_place_of_a_file_is_named(tmp_path):
    (tmp_path / "case.nc").mkdir()
    with pytest.raises(InputFileError, match=r"case\.nc: is a directory, not a file"):
        read_dataset(tmp_path / "case.nc", stage="contact")


def test_netcdf_library_failure_is_named_too(tmp_path, monkeypatch):
    """netCDF4 reports a failed write as RuntimeError ("NetCDF: HDF error"): named like any I/O failure."""
    from roughcontact.core.files import OutputFileError
    from roughcontact.pipeline.io import write_dataset

    def hdf_error(self, tmp, **kwargs):
        raise RuntimeError("NetCDF: HDF error")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", hdf_error)
    ds = xr.Dataset({"a": ("x", [1.0], {"units": "1", "long_name": "a"})},
                    coords={"x": ("x", [0], {"units": "1", "long_name": "x"})})
    with pytest.raises(OutputFileError, match=r"c\.nc: could not be written \(NetCDF: HDF error\)"):
        write_dataset(ds, tmp_path / "c.nc", stage="surface", scene="s", scene_parameters={})
    assert list(tmp_path.iterdir()) == []


def test_a_finished_job_logs_its_exact_cpu_and_memory_last(tmp_path):
    """run_logged's last line: the process's CPU (its work included) and peak RSS, as runcost reads them."""
    import logging
    import time

    from roughcontact.pipeline.io import JOB_COST_PATTERN, run_logged

    def work(logger):
        start = time.process_time()
        while time.process_time() - start < 0.3:  # 0.3 s of CPU, however long that takes
            sum(range(1000))
        logger.info("done")

    before = time.process_time()
    log = tmp_path / "job.log"
    run_logged(log, work)
    logging.getLogger("roughcontact").handlers.clear()
    last = log.read_text().splitlines()[-1]
    match = JOB_COST_PATTERN.search(last)
    assert match, last
    cpu, rss = float(match[1]), float(match[2])
    # the whole process's CPU so far, its waited-for children included (a job's subprocesses);
    # getrusage again for the upper bound: os.times() counts whole clock ticks (10 ms) per term
    import resource

    now = sum(r.ru_utime + r.ru_stime for r in (resource.getrusage(resource.RUSAGE_SELF),
                                                 resource.getrusage(resource.RUSAGE_CHILDREN)))
    assert before + 0.3 - 0.01 <= cpu <= now + 1e-3
    assert 10.0 < rss < 1e5, f"peak RSS {rss} MiB is not a pytest process's size"


@pytest.mark.parametrize("names", [["frt", "frt2", "ibwspot", "ünï-ß"], ["ibwspot", "frt2", "frt", "a"]])
def test_names_of_unequal_lengths_are_written_whole(tmp_path, names):
    # Per-case files read back carry their name's width in the encoding (dtype <U3); an aggregate
    # stacked from them must still write every name whole, in any order, with a shared prefix and
    # non-ASCII letters (once, "frt2" was written as "frt").
    from roughcontact.analysis.aggregate.combine import combine_topographies
    from roughcontact.pipeline.datasets import expand_case

    parts = []
    for k, name in enumerate(names):
        ds = expand_case(xr.Dataset({"epsilon": ((), float(k), {"units": "1", "long_name": "a value"})}),
                         topography=name)
        path = write_dataset(ds, tmp_path / f"case{k}.nc", stage="contact", scene="s", scene_parameters={})
        parts.append(read_dataset(path, stage="contact"))
    agg = combine_topographies(parts, [f"case{k}.nc" for k in range(len(names))], expected=names,
                               kind="representativity")
    path = write_dataset(agg, tmp_path / "agg.nc", stage="aggregate", scene="s", scene_parameters={})
    back = read_dataset(path, stage="aggregate")
    assert [str(t) for t in back["topography"].values] == names
    np.testing.assert_array_equal(back["epsilon"].values, np.arange(len(names), dtype=float))


def test_eta_from_the_recent_pace():
    from roughcontact.case.progress import eta

    assert eta([1.0, 1.0], 5) == "about 3 s left (3 of 5 to go)"
    # the last five steps set the pace (steps slow down as the contact grows)
    assert eta([100.0] + [2.0] * 5, 36) == "about 1 min 00 s left (30 of 36 to go)"
    assert eta([1.0] * 4, 4) == "done"


# --------------------------------------------------------------------------------- outputs checked before the work
def test_check_writable_names_a_folder_a_file_in_the_way_and_a_read_only_folder(tmp_path, monkeypatch):
    from roughcontact.core.files import check_writable

    assert check_writable(tmp_path / "a" / "b" / "out.nc") == tmp_path / "a" / "b" / "out.nc"
    assert not (tmp_path / "a").exists() and list(tmp_path.iterdir()) == []  # nothing created, no probe left
    with pytest.raises(ValueError, match=rf"^{tmp_path}: is a folder; give --out's file name"):
        check_writable(tmp_path, "--out")
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match=rf"{tmp_path}/f/out.nc: cannot be written: {tmp_path}/f is a file, not a "
                                         "folder; give the output another path"):
        check_writable(tmp_path / "f" / "out.nc")

    def refused(*args, **kwargs):  # a read-only mount (permission bits do not stop root)
        raise OSError(30, "Read-only file system")

    monkeypatch.setattr(os, "open", refused)
    with pytest.raises(ValueError, match=rf"{tmp_path}/out.nc: cannot be written \({tmp_path}: Read-only file "
                                         r"system\); give the output a writable folder"):
        check_writable(tmp_path / "out.nc")

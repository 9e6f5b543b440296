"""The same computation gives the same bytes in every process, even on a busy machine.

FFTW plans chosen by timing (``FFTW_MEASURE``) differ between processes that plan while
the machine is loaded, and different plans round differently in the last bits. The
package plans with ``FFTW_ESTIMATE`` (heuristics only), so surfaces and contact
solutions must hash identically across concurrent processes. The concurrency itself,
plus one CPU burner per core, loads the machine while the workers plan.
"""
import json
import os
import re
import subprocess
import sys
import textwrap
from collections import Counter

import numpy as np
import pytest

from roughcontact.core.fftw_library import mkl_installed

pytest.importorskip("pyfftw")

N_WORKERS = 8
TIMEOUT_S = 600  # generous: only a hung worker should ever reach it

WORKER = textwrap.dedent(
    """
    import hashlib, json
    from roughcontact.solver import solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    out = {}
    for n in (128, 256):
        h = generate_surface(n, 4, 32, 0.5, 1, rms_slope=0.1)
        out[f"surface N={n}"] = hashlib.sha256(h.tobytes()).hexdigest()
        # Solve on a surface made with numpy.fft so the solve is checked on its own.
        h = generate_surface(n, 4, 32, 0.5, 1, rms_slope=0.1, backend="numpy")
        ds = solve_contact(h, [0.001, 0.002, 0.003], store_fields=True)
        digest = hashlib.sha256()
        for name in sorted(ds.data_vars):
            if name != "wall_time":  # the only legitimately varying output
                digest.update(name.encode())
                digest.update(ds[name].values.tobytes())
        out[f"solve N={n}"] = digest.hexdigest()
        out[f"backend N={n}"] = ds.attrs["fft_backend"]
    print("@@RESULT@@" + json.dumps(out), flush=True)
    """
)

BURNER = "import time\nend = time.monotonic() + 600\nwhile time.monotonic() < end:\n    pass\n"


# ROUGHCONTACT_FFT=mkl (Intel MKL under pyFFTW, core.fftw_library: no planner, no wisdom) on half the workers:
# the same check of MKL's own determinism at half the cost
@pytest.mark.parametrize(("library", "n_workers", "label"), [("pyfftw", N_WORKERS, "pyfftw"),
                                                             ("mkl", N_WORKERS // 2, "pyfftw-mkl")])
@pytest.mark.slow
def test_fft_results_identical_across_concurrent_processes(tmp_path, library, n_workers, label):
    if library == "mkl" and not mkl_installed():
        pytest.skip("mkl-service is not installed (pip install -e '.[mkl]')")
    env = dict(os.environ, ROUGHCONTACT_FFT=library, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    script = tmp_path / "worker.py"
    script.write_text(WORKER)
    burners = [subprocess.Popen([sys.executable, "-c", BURNER]) for _ in range(os.cpu_count() or 1)]
    try:
        workers = [
            subprocess.Popen([sys.executable, str(script)], env=env, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
            for _ in range(n_workers)
        ]
        results = []
        for i, proc in enumerate(workers):
            try:
                stdout, stderr = proc.communicate(timeout=TIMEOUT_S)
            except subprocess.TimeoutExpired:
                for p in workers:
                    p.kill()
                pytest.fail(f"worker {i} still running after {TIMEOUT_S} s (hung?)")
            assert proc.returncode == 0, f"worker {i} exited with {proc.returncode}:\n{stderr}"
            line = [ln for ln in stdout.splitlines() if ln.startswith("@@RESULT@@")]
            assert line, f"worker {i} printed no result:\n{stdout}\n{stderr}"
            results.append(json.loads(line[-1][len("@@RESULT@@"):]))
    finally:
        for b in burners:
            b.kill()
        for b in burners:
            b.wait()
    assert all(r[k] == label for r in results for k in r if k.startswith("backend")), results
    differing = {}
    for key in results[0]:
        counts = Counter(r[key] for r in results)
        if len(counts) > 1:
            differing[key] = sorted(counts.values(), reverse=True)
    assert not differing, (
        f"{n_workers} concurrent processes computed different bytes (group sizes of equal hashes): "
        f"{differing}; FFT plans are not deterministic (timing-based planning?)"
    )


@pytest.mark.parametrize("n", [96, 128])  # 128 has a shipped plan, 96 not
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_estimate_plan_ignores_measured_wisdom(n):
    """A timed plan made earlier in the process must not replace the ESTIMATE choice.

    FFTW reuses wisdom from a more rigorous planner (MEASURE, PATIENT), so without
    forgetting it the package's plan would depend on what else ran in the process.
    Checked in a fresh subprocess: the bytes after a PATIENT plan of the same shape equal
    the plain ones (without ``pyfftw.forget_wisdom()`` in RealFFT2 they differ).
    """
    code = textwrap.dedent(
        """
        import hashlib, json, sys
        import numpy as np, pyfftw
        from roughcontact.core.fft import RealFFT2
        n = int(sys.argv[1])
        a = np.random.default_rng(0).standard_normal((n, n))
        def digest():
            f = RealFFT2((n, n), backend="pyfftw")
            return hashlib.sha256(f.forward(a).tobytes() + f.backward(f.forward(a)).tobytes()).hexdigest()
        plain = digest()
        r = pyfftw.empty_aligned((n, n), dtype="float64")
        s = pyfftw.empty_aligned((n, n // 2 + 1), dtype="complex128")
        pyfftw.FFTW(r, s, axes=(0, 1), flags=("FFTW_PATIENT",))
        print(json.dumps([plain, digest()]))
        """
    )
    proc = subprocess.run([sys.executable, "-c", code, str(n)], capture_output=True, text=True,
                          timeout=TIMEOUT_S, env=dict(os.environ, OMP_NUM_THREADS="1"))
    assert proc.returncode == 0, proc.stderr
    plain, after = json.loads(proc.stdout.strip().splitlines()[-1])
    assert plain == after, "the ESTIMATE plan changed after a PATIENT plan of the same shape (wisdom reused)"



def test_shipped_plans_are_loaded_before_planning(monkeypatch):
    # The measured plans shipped with the package are in FFTW's store when a pair is planned.
    pyfftw = pytest.importorskip("pyfftw")
    from roughcontact.core import fft

    shipped = fft.shipped_wisdom()
    assert shipped is not None, "src/roughcontact/fftw_wisdom.json is missing"
    stores = []
    real_fftw = pyfftw.FFTW

    def spy(*args, **kwargs):
        stores.append(pyfftw.export_wisdom())
        return real_fftw(*args, **kwargs)

    monkeypatch.setattr(fft.pyfftw, "FFTW", spy)
    fft.RealFFT2((1024, 1024), backend="pyfftw", dtype=np.float32)
    assert len(stores) == 2  # forward and backward
    for store in stores:
        for mine, theirs in zip(shipped[:2], store[:2], strict=True):
            entries = [line.strip() for line in mine.decode().splitlines()[1:-1]]
            assert entries and all(e in theirs.decode() for e in entries)


def test_planning_keeps_the_callers_wisdom():
    """Another pyFFTW user's wisdom survives this package's planning, entry for entry."""
    pyfftw = pytest.importorskip("pyfftw")
    from roughcontact.core.fft import RealFFT2

    pyfftw.forget_wisdom()
    r = pyfftw.empty_aligned((24, 24), dtype="float64")
    s = pyfftw.empty_aligned((24, 13), dtype="complex128")
    pyfftw.FFTW(r, s, axes=(0, 1), flags=("FFTW_MEASURE",))  # the caller's measured plan
    theirs = pyfftw.export_wisdom()
    assert len(theirs[0].decode().splitlines()) > 2, "the caller's plan left no wisdom to keep"
    RealFFT2((64, 64), backend="pyfftw")

    def entries(store):  # FFTW's export order is its hash table's, not the plans'
        return [sorted(w.decode().splitlines()) for w in store]

    assert entries(pyfftw.export_wisdom()) == entries(theirs)


def test_write_wisdom_round_trip(tmp_path, monkeypatch):
    pytest.importorskip("pyfftw")
    from roughcontact.core import fft

    path = fft.write_wisdom(tmp_path / "w.json", sizes=(8, 16))
    monkeypatch.setattr(fft, "WISDOM_FILE", path)
    fft.shipped_wisdom.cache_clear()
    try:
        double, single, _ = fft.shipped_wisdom()
        assert double.startswith(b"(fftw-") and single.startswith(b"(fftw-")
        data = json.loads(path.read_text())
        assert data["sizes"] == [8, 16] and "flags" not in data
        assert data["machines"][fft.machine_key()]["flags"] == {"8": ["FFTW_PATIENT"], "16": ["FFTW_PATIENT"]}
    finally:
        monkeypatch.undo()
        fft.shipped_wisdom.cache_clear()


def _wisdom_of_two_models(fft, tmp_path, monkeypatch):
    """A wisdom file of 8 x 8 plans written as "CPU A" (the default), then "CPU B"; ``(path, data)``."""
    path = tmp_path / "w.json"
    for model in ("CPU A", "CPU B"):
        monkeypatch.setattr(fft, "machine_key", lambda m=model: m)
        fft.write_wisdom(path, sizes=(8,))
    return path, json.loads(path.read_text())


def test_wisdom_is_chosen_by_processor_model(tmp_path, monkeypatch):
    """Plans are filed per processor model; another model gets the file's default set."""
    pytest.importorskip("pyfftw")
    from roughcontact.core import fft

    shipped_file = fft.WISDOM_FILE
    path, data = _wisdom_of_two_models(fft, tmp_path, monkeypatch)
    assert set(data["machines"]) == {"CPU A", "CPU B"} and data["default"] == "CPU A"
    data["machines"]["CPU A"]["single"] = "(fftw-3.3.5 fftwf_wisdom #x0\n)"  # tell the sets apart
    path.write_text(json.dumps(data))
    monkeypatch.setattr(fft, "WISDOM_FILE", path)
    try:
        for model, expect_a in (("CPU A", True), ("CPU B", False), ("CPU C", True)):
            monkeypatch.setattr(fft, "machine_key", lambda m=model: m)
            fft.shipped_wisdom.cache_clear()
            assert (fft.shipped_wisdom()[1] == b"(fftw-3.3.5 fftwf_wisdom #x0\n)") == expect_a, model
    finally:
        fft.shipped_wisdom.cache_clear()
    # the shipped file names this machine's model or falls back to its default, and has plans up to 8192
    shipped = json.loads(shipped_file.read_text()) if shipped_file.exists() else None
    if shipped is not None:
        assert shipped["default"] in shipped["machines"] and max(shipped["sizes"]) == 8192


def test_wisdom_sets_record_their_planner_flags(tmp_path, monkeypatch):
    """Each processor's set names the flags asked for at each side; a file that named them once keeps them.

    Sides above ``WISDOM_PATIENT_MAX`` are measured with FFTW_MEASURE (PATIENT's planning is too slow there).
    """
    pytest.importorskip("pyfftw")
    from roughcontact.core import fft

    path = tmp_path / "w.json"
    monkeypatch.setattr(fft, "machine_key", lambda: "CPU A")
    fft.write_wisdom(path, sizes=(8, 16), flags=("FFTW_MEASURE",))
    data = json.loads(path.read_text())
    # the format before flags per set: one list for the file
    data["flags"] = data["machines"]["CPU A"].pop("flags")["8"]
    path.write_text(json.dumps(data))
    monkeypatch.setattr(fft, "machine_key", lambda: "CPU B")
    monkeypatch.setattr(fft, "WISDOM_PATIENT_MAX", 8)
    fft.write_wisdom(path, sizes=(8, 16))
    after = json.loads(path.read_text())
    assert "flags" not in after and after["default"] == "CPU A"
    assert after["machines"]["CPU A"]["flags"] == {"8": ["FFTW_MEASURE"], "16": ["FFTW_MEASURE"]}
    assert after["machines"]["CPU B"]["flags"] == {"8": ["FFTW_PATIENT"], "16": ["FFTW_MEASURE"]}
    assert after["machines"]["CPU A"]["single"] == data["machines"]["CPU A"]["single"]


def test_write_wisdom_keep_measures_only_what_is_missing(tmp_path, monkeypatch):
    """``keep=True`` keeps this model's plans entry for entry and fills the default set's gaps."""
    pytest.importorskip("pyfftw")
    from roughcontact.core import fft

    path, data = _wisdom_of_two_models(fft, tmp_path, monkeypatch)  # now "CPU B"

    def entries(text):
        return {line.strip() for line in text.splitlines()[1:] if line.strip().startswith("(")}

    # take CPU A's (the default's) in-place plans away, as in a file from before they existed
    single_b = entries(data["machines"]["CPU B"]["single"])
    a_text = data["machines"]["CPU A"]["single"]
    kept = [line for line in a_text.splitlines() if "rdft2" not in line or line.strip() == ")"]
    data["machines"]["CPU A"]["single"] = "\n".join(kept) + "\n"
    path.write_text(json.dumps(data))
    fft.write_wisdom(path, sizes=(8,), keep=True)  # as CPU B
    after = json.loads(path.read_text())
    assert entries(after["machines"]["CPU B"]["single"]) == single_b  # B's plans kept, none re-measured
    default = entries(after["machines"]["CPU A"]["single"])
    assert entries("\n".join(kept)) <= default  # A's own plans kept
    assert any("rdft2" in e for e in default)  # the gaps filled from B's
    assert after["machines"]["CPU A"]["single"].rstrip().endswith(")")
    pyfftw = pytest.importorskip("pyfftw")
    pyfftw.forget_wisdom()
    assert pyfftw.import_wisdom(tuple(after["machines"]["CPU A"][k].encode() for k in fft._PRECISIONS))[1]


def test_shipped_plans_cover_the_in_place_product():
    """The float32 product of the solver's loop (in place) is planned from the shipped wisdom at N = 1024.

    Planned with no wisdom (FFTW_ESTIMATE's own heuristics) it cost 1.3-1.5x the measured plan's
    time on the AMD EPYC (2026-11-26); planning it with the shipped wisdom must add no entry.
    """
    pyfftw = pytest.importorskip("pyfftw")
    from roughcontact.core import fft
    from roughcontact.core.backend import SpectralProduct, get_backend

    shipped = fft.shipped_wisdom()
    created = []
    real_fftw = pyfftw.FFTW

    def spy(*args, **kwargs):
        plan = real_fftw(*args, **kwargs)
        created.append(pyfftw.export_wisdom()[1])
        return plan

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(fft.pyfftw, "FFTW", spy)
        SpectralProduct(get_backend("numpy"), (1024, 1024), np.float32)
    assert len(created) == 2  # the forward and the inverse
    mine = {line.strip() for line in shipped[1].decode().splitlines()[1:-1]}
    for store in created:
        assert {line.strip() for line in store.decode().splitlines()[1:-1]} == mine


def test_slab_plans_join_the_set_and_replace_only_what_fftw_rejects(tmp_path, monkeypatch):
    """``slabs.write_wisdom`` (``fft.add_plans``) appends the slab plans to the set, keeps the set's own lines,
    records what it planned, and replaces a set's entry only where FFTW cannot apply it to a planned problem."""
    pyfftw = pytest.importorskip("pyfftw")
    from roughcontact.core import fft
    from roughcontact.solver.mpi import slabs

    monkeypatch.setattr(fft, "machine_key", lambda: "CPU A")
    path = fft.write_wisdom(tmp_path / "w.json", sizes=(8,))
    base = json.loads(path.read_text())["machines"]["CPU A"]
    kw = {"sizes": (32,), "ranks": (2,), "tiles": (1,)}
    slabs.write_wisdom(path, **kw)
    after = json.loads(path.read_text())["machines"]["CPU A"]
    assert after["slabs"] == {"sizes": [32], "tiles": [1], "ranks": [2], "flags": ["FFTW_MEASURE"]}
    for k in ("double", "single"):
        old, new = base[k].splitlines(), after[k].splitlines()
        assert new[:len(old) - 1] == old[:-1] and len(new) > len(old) and new[-1] == ")"

    def rejected(entries):
        return fft._rejected(tuple(entries[k] for k in fft._PRECISIONS), slabs.slab_problems(**kw))

    assert rejected(after) == 0
    # a set naming a codelet of another size for one of those problems: FFTW cannot apply it
    lines = after["single"].splitlines()
    at = next(i for i in range(len(base["single"].splitlines()) - 1, len(lines))
              if re.search(r"codelet_n1[fb]v_32_", lines[i]))
    wrong = lines[at].replace("v_32_", "v_16_")
    bad = base | {"single": "\n".join([*base["single"].splitlines()[:-1], wrong, ")"]) + "\n"}
    assert rejected(bad) > 0
    data = json.loads(path.read_text())
    data["machines"]["CPU A"] = bad
    path.write_text(json.dumps(data))
    slabs.write_wisdom(path, **kw)
    fixed = json.loads(path.read_text())["machines"]["CPU A"]
    assert wrong not in fixed["single"] and rejected(fixed) == 0
    assert fixed["single"].splitlines()[:len(base["single"].splitlines()) - 1] == base["single"].splitlines()[:-1]
    assert fixed["double"].splitlines()[:len(base["double"].splitlines()) - 1] == base["double"].splitlines()[:-1]
    pyfftw.forget_wisdom()


def test_adding_plans_to_a_file_of_the_first_format_is_refused_with_its_remedy(tmp_path):
    """``add_plans`` on a wisdom file of one unnamed set names the file and says to write it again first."""
    pytest.importorskip("pyfftw")
    from roughcontact.solver.mpi import slabs

    path = tmp_path / "old.json"
    text = json.dumps({"machine": "CPU A", "double": "(fftw-3.3.5 fftw_wisdom #x0\n)\n",
                       "single": "(fftw-3.3.5 fftwf_wisdom #x0\n)\n",
                       "long_double": "(fftw-3.3.5 fftwl_wisdom #x0\n)\n"})
    path.write_text(text)
    with pytest.raises(ValueError, match=r"old\.json: a wisdom file of the first format .* write it again with "
                                         r"write_wisdom\(\) before adding plans to it"):
        slabs.write_wisdom(path, sizes=(32,), ranks=(2,), tiles=(1,))
    assert path.read_text() == text  # untouched

"""The FFT library a solve names is the one it ran (``ROUGHCONTACT_FFT``, roughcontact.core.fft.default_backend).

``ROUGHCONTACT_FFT=numpy`` asks for no FFTW: the single solve, a batch and the MPI ranks' slab transforms then
make no pyFFTW plan, and the outputs' ``fft_backend`` says ``numpy`` (until 2026-12-05 a batch and the MPI
ranks planned with pyFFTW whatever the variable said, while a batch's output said ``numpy``). Where Intel MKL
was loaded into the process before pyFFTW (``ROUGHCONTACT_FFT=mkl`` or another library), MKL's FFTW3 interface
answers pyFFTW's calls, and the outputs say ``pyfftw-mkl`` (core.fftw_library.pyfftw_library); the MPI ranks' slab
transforms run on MKL too (planned on views with one batch axis: MKL's interface plans no 1-D transform batched over
two, and until 2026-12-05 they were SciPy's there) and say ``mpi-slab-mkl``. The answers agree with FFTW's to the
contact area's node: the libraries' transforms differ in the last bits.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from roughcontact.core.fftw_library import mkl_installed
from roughcontact.solver import solve_contact
from roughcontact.solver.batch import solve_contact_batch
from roughcontact.surfaces.synthetic import generate_surface
from test_solver_mpi import MPIEXEC

pyfftw = pytest.importorskip("pyfftw")


@pytest.fixture
def plans_made(monkeypatch):
    """The shapes of the inputs of every pyFFTW plan made while the test runs."""
    made = []

    class Counting(pyfftw.FFTW):
        def __init__(self, input_array, *args, **kwargs):
            made.append(input_array.shape)
            super().__init__(input_array, *args, **kwargs)

    monkeypatch.setattr(pyfftw, "FFTW", Counting)
    return made


def _surfaces(n=48, cases=2):
    return np.stack([generate_surface(n, 4, 16, 0.8, seed, rms_slope=0.1) for seed in range(cases)])


def test_asking_for_numpy_makes_no_fftw_plan_and_says_so(plans_made, monkeypatch):
    hs, loads = _surfaces(), [1e-3, 3e-3]
    plans_made.clear()  # the surfaces' own transforms, FFTW's
    monkeypatch.setenv("ROUGHCONTACT_FFT", "numpy")
    single = solve_contact(hs[0], loads)
    batch = solve_contact_batch(hs, loads)
    assert plans_made == []
    assert single.attrs["fft_backend"] == batch.attrs["fft_backend"] == "numpy"
    monkeypatch.setenv("ROUGHCONTACT_FFT", "pyfftw")
    fftw = solve_contact_batch(hs, loads)
    assert fftw.attrs["fft_backend"] == "pyfftw" and plans_made  # the batch's own plans (not cached)
    assert bool(batch.converged.all()) and bool(fftw.converged.all())
    nodes = np.abs(batch.area_fraction.values - fftw.area_fraction.values) * hs[0].size
    assert nodes.max() <= 1 + 1e-9


_SLAB = textwrap.dedent(
    """
    from mpi4py import MPI
    from roughcontact.solver.mpi.slabs import Slabs, make_fft
    fft = make_fft("slab", MPI.COMM_SELF, Slabs((32, 24), 1, 0))
    print(type(fft).__name__, fft.name)
    """
)


@pytest.mark.parametrize(("library", "kind"), [
    ("numpy", ["SlabFFT", "slab-scipy"]), ("pyfftw", ["FftwSlabFFT", "slab"]), ("mkl", ["FftwSlabFFT", "slab-mkl"])])
def test_the_mpi_slab_transforms_follow_the_variable(library, kind):
    """SciPy's slab transforms where no FFTW is asked for; pyFFTW's planned ones where FFTW or MKL answers it; each
    named (the outputs' ``fft_backend`` is ``"mpi-" + name``)."""
    pytest.importorskip("mpi4py")
    if library == "mkl":
        if not mkl_installed():  # found, not imported: MKL would stay loaded under this process' FFTW users
            pytest.skip("mkl-service is not installed (pip install -e '.[mkl]')")
    env = dict(os.environ, ROUGHCONTACT_FFT=library)
    res = subprocess.run([sys.executable, "-c", _SLAB], capture_output=True, text=True, env=env, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.split() == kind


def test_pyfftws_own_fftw_is_told_from_mkls_interface(monkeypatch):
    from roughcontact.core import fftw_library as backend

    assert backend.pyfftw_library.__wrapped__() == "fftw"  # this process: pyFFTW's FFTW exports its wisdom
    fftwl = pyfftw.export_wisdom()[2]
    monkeypatch.setattr(pyfftw, "export_wisdom", lambda: (b"", b"", fftwl))  # MKL's interface keeps none
    monkeypatch.setattr(backend, "_global_symbol", lambda name: name == "DftiCreateDescriptor")
    assert backend.pyfftw_library.__wrapped__() == "mkl"
    monkeypatch.setattr(backend, "_global_symbol", lambda name: False)
    assert backend.pyfftw_library.__wrapped__() == "other"


def test_the_outputs_name_mkl_where_it_answers_pyfftw(monkeypatch):
    from roughcontact.core import fftw_library as backend

    hs = _surfaces()
    monkeypatch.setenv("ROUGHCONTACT_FFT", "pyfftw")
    monkeypatch.setattr(backend, "pyfftw_library", lambda: "mkl")
    assert solve_contact(hs[0], [1e-3]).attrs["fft_backend"] == "pyfftw-mkl"
    assert solve_contact(hs[0], [1e-3], boundary="free").attrs["fft_backend"] == "pyfftw-mkl"
    assert solve_contact_batch(hs, [1e-3]).attrs["fft_backend"] == "pyfftw-mkl"
    monkeypatch.setenv("ROUGHCONTACT_FFT", "numpy")
    assert solve_contact(hs[0], [1e-3]).attrs["fft_backend"] == "numpy"


_MKL_FIRST = textwrap.dedent(
    """
    import sys
    if sys.argv[1] == "import mkl":
        import mkl  # noqa: F401  (mkl-service: MKL's runtime loaded with RTLD_GLOBAL, before pyFFTW)
    import numpy as np
    from mpi4py import MPI
    from roughcontact.core.fftw_library import pyfftw_library
    from roughcontact.solver import solve_contact
    from roughcontact.solver.batch import solve_contact_batch
    from roughcontact.solver.mpi.run import solve_contact_mpi
    from roughcontact.surfaces.synthetic import generate_surface
    h = generate_surface(64, 4, 16, 0.8, 0, rms_slope=0.1)
    loads = [1e-3, 3e-3]
    runs = [solve_contact(h, loads), solve_contact(h, loads, boundary="free"), solve_contact_batch(h[None], loads),
            solve_contact_mpi(h, h.shape, loads, comm=MPI.COMM_SELF)]
    print(pyfftw_library(), *[ds.attrs["fft_backend"] for ds in runs])
    print(*[int(round(a * h.size)) for ds in runs for a in np.ravel(ds.area_fraction.values)])
    """
)


def _run(code, *args, **env):
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300,
                          env={**os.environ, **env})


def test_mkl_answering_pyfftw_is_what_the_outputs_say():
    """MKL under pyFFTW, asked for (``ROUGHCONTACT_FFT=mkl``) or loaded by someone else first (``import mkl``): the
    outputs say so, and the contact areas are FFTW's to the node."""
    pytest.importorskip("mpi4py")
    if not mkl_installed():
        pytest.skip("mkl-service is not installed (pip install -e '.[mkl]')")
    out = {}
    for name, args, env in (("fftw", ["plain"], {"ROUGHCONTACT_FFT": "pyfftw"}),
                            ("import mkl", ["import mkl"], {"ROUGHCONTACT_FFT": "pyfftw"}),
                            ("asked", ["plain"], {"ROUGHCONTACT_FFT": "mkl"})):
        res = _run(_MKL_FIRST, *args, **env)
        assert res.returncode == 0, res.stderr
        out[name] = [line.split() for line in res.stdout.splitlines()[-2:]]
    assert out["fftw"][0] == ["fftw", "pyfftw", "pyfftw", "pyfftw", "mpi-slab"]
    for name in ("import mkl", "asked"):
        assert out[name][0] == ["mkl", "pyfftw-mkl", "pyfftw-mkl", "pyfftw-mkl", "mpi-slab-mkl"], name
        nodes = np.abs(np.array(out["fftw"][1], int) - np.array(out[name][1], int))
        assert nodes.max() <= 1, (name, out["fftw"][1], out[name][1])


_TOO_LATE = textwrap.dedent(
    """
    import sys
    if sys.argv[1] == "pyfftw first":
        import pyfftw  # noqa: F401  (bound to its own FFTW before roughcontact could load MKL)
    else:
        sys.modules["mkl"] = None  # mkl-service missing
    import numpy as np
    from roughcontact.solver import solve_contact
    try:
        solve_contact(np.random.default_rng(0).random((16, 16)), [1e-3])
    except ValueError as err:
        print("refused:", err)
    """
)


@pytest.mark.parametrize(("case", "says"), [
    ("pyfftw first", "takes effect only where it is set before the process first imports pyFFTW"),
    ("no mkl", r"Intel MKL cannot be loaded .*pip install -e '\.\[mkl\]'")])
def test_asking_for_mkl_where_it_cannot_answer_is_refused_with_the_remedy(case, says):
    res = _run(_TOO_LATE, case, ROUGHCONTACT_FFT="mkl")
    assert res.returncode == 0, res.stderr
    assert res.stdout.startswith("refused: ROUGHCONTACT_FFT=mkl"), res.stdout
    assert re.search(says, res.stdout), res.stdout


_RANKS = textwrap.dedent(
    """
    import numpy as np
    from mpi4py import MPI
    from roughcontact.solver.mpi.run import solve_contact_mpi
    from roughcontact.solver.mpi.slabs import Slabs
    from roughcontact.surfaces.synthetic import generate_surface
    h = generate_surface(96, 4, 16, 0.8, 0, rms_slope=0.1)
    slabs = Slabs(h.shape, MPI.COMM_WORLD.size, MPI.COMM_WORLD.rank)
    ds = solve_contact_mpi(h[slabs.x0:slabs.x1], h.shape, [1e-3, 3e-3, 5e-3], comm=MPI.COMM_WORLD)
    if ds is not None:
        print(ds.attrs["fft_backend"], bool(ds.converged.all()))
        print(*np.round(ds.area_fraction.values * h.size).astype(int))
    """
)


@pytest.mark.parametrize("ranks", [2, 3])
def test_mpi_ranks_on_mkl_plan_their_slab_transforms_there(ranks):
    """``ROUGHCONTACT_FFT=mkl`` over MPI ranks (96 rows: 3 ranks hold 32 each, their 49 spectral columns 17, 16, 16):
    the slabs' 1-D transforms planned on MKL, every step converged, the contact areas FFTW's to the node."""
    pytest.importorskip("mpi4py")
    if not mkl_installed():
        pytest.skip("mkl-service is not installed (pip install -e '.[mkl]')")
    if MPIEXEC is None:
        pytest.skip("mpi4py or mpiexec not installed (pip install -e '.[mpi]')")
    out = {}
    for library in ("pyfftw", "mkl"):
        res = subprocess.run([MPIEXEC, "-n", str(ranks), sys.executable, "-c", _RANKS], capture_output=True,
                             text=True, timeout=300, env={**os.environ, "ROUGHCONTACT_FFT": library})
        assert res.returncode == 0, res.stderr[-3000:]
        out[library] = [line.split() for line in res.stdout.splitlines()[-2:]]
    assert out["pyfftw"][0] == ["mpi-slab", "True"] and out["mkl"][0] == ["mpi-slab-mkl", "True"]
    nodes = np.abs(np.array(out["pyfftw"][1], int) - np.array(out["mkl"][1], int))
    assert nodes.max() <= 1, out

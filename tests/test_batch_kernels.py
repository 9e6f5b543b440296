"""The fused CUDA kernels of the batched solve, run on the host: their C code compiled by a C++ compiler.

CI has no GPU, and the CuPy kernels of :mod:`roughcontact.solver.batch.cuda` are C code that
only CuPy compiles. Here a stand-in CuPy builds ``ElementwiseKernel`` and ``ReductionKernel`` as
CuPy does in spirit (the parameters declared per element, outputs by reference, the reduction's
``a``/``b`` accumulators, broadcasting of per-case inputs) around the very same code strings,
compiles them with ``g++`` and calls them with ctypes. The tests then check (1) each fused kernel
against its plain array expression through :class:`CupyKernels`' own wrappers (argument order,
outputs updated in place) and its self-check, which must keep every kernel, and (2) a whole
batched solve with the fused kernels against the numpy backend's. What this cannot check is
CuPy itself (its parsing of the parameters, its launch); benchmarks/gpu/run.sh does, on a GPU.
Skipped where no C++ compiler is installed.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import shutil
import subprocess
import sys
import types
import warnings

import numpy as np
import pytest

from roughcontact.core.backend import get_backend
from roughcontact.solver.batch import cuda as batch_cuda, kernels as batch_kernels, solve_contact_batch
from roughcontact.surfaces.synthetic import generate_surface

CXX = shutil.which("g++") or shutil.which("c++")
pytestmark = pytest.mark.skipif(CXX is None, reason="no C++ compiler to run the kernels' C code")

CTYPES = {"float64": "double", "float32": "float", "bool": "bool", "int32": "int", "int64": "long long"}
DTYPES = {"float64": np.float64, "float32": np.float32, "bool": np.bool_, "int32": np.int32, "int64": np.int64}
PRELUDE = ("#include <cmath>\n#include <algorithm>\n"
           "using std::fabs; using std::fmax; using std::max; using std::min; using std::isfinite;\n")


def _params(text: str) -> list[tuple[str, str]]:
    return [tuple(p.split()) for p in text.split(",")]


@functools.cache
def _compile(code: str, tmpdir: str):
    key = hashlib.sha1(code.encode()).hexdigest()[:16]
    src, lib = f"{tmpdir}/k{key}.cpp", f"{tmpdir}/k{key}.so"
    with open(src, "w") as fh:
        fh.write(code)
    subprocess.run([CXX, "-O1", "-shared", "-fPIC", "-o", lib, src], check=True, capture_output=True)
    return ctypes.CDLL(lib)


def _ptr(a):
    return a.ctypes.data_as(ctypes.c_void_p)


class _Elementwise:
    """``cupy.ElementwiseKernel`` on the host: one C++ loop over the broadcast elements."""

    def __init__(self, tmpdir, in_params, out_params, operation, name="kernel"):
        self.ins, self.outs = _params(in_params), _params(out_params)
        decl = [f"const {CTYPES[t]}* _raw_{n}" for t, n in self.ins] + [f"{CTYPES[t]}* _raw_{n}" for t, n in self.outs]
        body = "".join(f"const {CTYPES[t]} {n} = _raw_{n}[i];\n" for t, n in self.ins)
        body += "".join(f"{CTYPES[t]}& {n} = _raw_{n}[i];\n" for t, n in self.outs)
        code = (f"{PRELUDE}extern \"C\" void run(long _n, {', '.join(decl)}) {{\n"
                f"for (long i = 0; i < _n; ++i) {{\n{body}{operation};\n}}\n}}\n")
        self.fn = _compile(code, tmpdir).run

    def __call__(self, *args):
        ins, outs = args[:len(self.ins)], list(args[len(self.ins):])
        assert len(outs) in (0, len(self.outs)), "CuPy takes all outputs or none"
        ins = [np.asarray(a, dtype=DTYPES[t]) for a, (t, _) in zip(ins, self.ins, strict=True)]
        shape = np.broadcast_shapes(*(a.shape for a in ins), *(o.shape for o in outs))
        ins = [np.ascontiguousarray(np.broadcast_to(a, shape)) for a in ins]
        for (t, _), o in zip(self.outs, outs, strict=False):
            assert o.shape == shape and o.flags.c_contiguous and o.dtype == DTYPES[t]
        outs += [np.empty(shape, dtype=DTYPES[t]) for t, _ in self.outs[len(outs):]]
        self.fn(ctypes.c_long(int(np.prod(shape))), *(_ptr(a) for a in ins + outs))
        return outs[0] if len(outs) == 1 else tuple(outs)


class _Reduction:
    """``cupy.ReductionKernel`` on the host for ``axis=(1, 2), keepdims=True``: per case, map then reduce."""

    def __init__(self, tmpdir, in_params, out_params, map_expr, reduce_expr, post_map_expr, identity, name="r"):
        self.ins = _params(in_params)
        (ot, on), = _params(out_params)
        self.out_dtype = DTYPES[ot]
        rt = CTYPES[ot]
        decl = [f"const {CTYPES[t]}* _raw_{n}" for t, n in self.ins] + [f"{rt}* _raw_{on}"]
        body = "".join(f"const {CTYPES[t]} {n} = _raw_{n}[_k];\n" for t, n in self.ins)
        code = (f"{PRELUDE}#define REDUCE(a, b) ({reduce_expr})\n"
                f"extern \"C\" void run(long _B, long _m, {', '.join(decl)}) {{\n"
                f"for (long _c = 0; _c < _B; ++_c) {{\n{rt} _acc = ({rt})({identity});\n"
                f"for (long _i = 0; _i < _m; ++_i) {{\nlong _k = _c * _m + _i;\n{body}"
                f"{rt} _v = ({map_expr});\n_acc = REDUCE(_acc, _v);\n}}\n"
                f"{rt}& {on} = _raw_{on}[_c];\n{{ {rt} a = _acc; {post_map_expr}; }}\n}}\n}}\n")
        self.fn = _compile(code, tmpdir).run

    def __call__(self, *args, axis=None, keepdims=False):
        assert axis == (1, 2) and keepdims
        ins = [np.asarray(a, dtype=DTYPES[t]) for a, (t, _) in zip(args, self.ins, strict=True)]
        shape = np.broadcast_shapes(*(a.shape for a in ins))
        ins = [np.ascontiguousarray(np.broadcast_to(a, shape)) for a in ins]
        out = np.empty((shape[0], 1, 1), dtype=self.out_dtype)
        self.fn(ctypes.c_long(shape[0]), ctypes.c_long(shape[1] * shape[2]), *(_ptr(a) for a in ins), _ptr(out))
        return out


def _compiled_cupy(tmpdir) -> types.ModuleType:
    """numpy under CuPy's names, with the two kernel classes compiled on the host."""
    fake = types.ModuleType("cupy")
    fake.__getattr__ = lambda name: getattr(np, name)
    fake.asnumpy = np.asarray
    fake.ndarray = type("ndarray", (), {})
    fake.cuda = types.SimpleNamespace(runtime=types.SimpleNamespace(getDeviceCount=lambda: 1))
    fake.ElementwiseKernel = functools.partial(_Elementwise, tmpdir)
    fake.ReductionKernel = functools.partial(_Reduction, tmpdir)
    return fake


@pytest.fixture(scope="module")
def kernel_dir(tmp_path_factory):
    return str(tmp_path_factory.mktemp("kernels"))  # one compilation of each kernel for the module


@pytest.fixture
def compiled_cupy(monkeypatch, kernel_dir):
    fake = _compiled_cupy(kernel_dir)
    monkeypatch.setitem(sys.modules, "cupy", fake)
    get_backend.cache_clear()
    yield fake
    get_backend.cache_clear()


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_every_fused_kernel_passes_its_self_check(compiled_cupy):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a kernel replaced by its plain form warns
        kernels = batch_cuda.fused_kernels(compiled_cupy)
    assert isinstance(kernels, batch_cuda.CupyKernels) and kernels.fused
    assert set(kernels.FUSED) <= {m for m in dir(batch_kernels.ArrayKernels) if not m.startswith("_")}


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_a_wrong_kernel_is_replaced_by_its_plain_form(compiled_cupy, monkeypatch):
    """A kernel whose result differs from the plain expression's is dropped, with a warning."""
    monkeypatch.setitem(batch_cuda.REDUCTIONS, "_dot", ("float64 u, float64 v", "float64 y", "u + v",
                                                           "a + b", "y = a", "0"))
    with pytest.warns(RuntimeWarning, match="fused kernel 'dot' failed its check"):
        kernels = batch_cuda.fused_kernels(compiled_cupy)
    assert not kernels.fused
    x = np.random.default_rng(1).random((2, 4, 4))
    np.testing.assert_allclose(kernels.dot(x, x), np.sum(x * x, axis=(1, 2), keepdims=True))


def test_batched_solve_with_the_fused_kernels(compiled_cupy):
    """The whole batched solve through the CuPy backend with the fused kernels (their C code compiled
    on the host) agrees with the numpy backend's plain expressions."""
    h = np.stack([generate_surface(64, 2, 16, 0.8, s, rms_slope=0.1) for s in range(2)])
    loads = np.linspace(0.0005, 0.005, 4)
    ref = solve_contact_batch(h, loads)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        got = solve_contact_batch(h, loads, array_backend="cupy")
    assert got.attrs["fft_backend"] == "cupy" and bool(got.converged.values.all())
    np.testing.assert_array_equal(got.iterations.values, ref.iterations.values)
    assert np.max(np.abs(got.area_fraction.values - ref.area_fraction.values)) <= 1.0 / 64**2
    np.testing.assert_allclose(got.mean_gap.values, ref.mean_gap.values, rtol=1e-9)

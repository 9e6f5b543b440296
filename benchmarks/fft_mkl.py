"""Intel MKL's FFTs beside the solver's pyFFTW: ``mkl_fft``, MKL under pyFFTW, and what loading MKL does to Tamaas.

benchmarks/README.md, "Intel MKL's FFTs: under pyFFTW as an option, and what they do to Tamaas". ``--on-mkl`` and
``--on-mkl-scan`` need the package's ``mkl`` extra (``pip install -e '.[mkl]'``: mkl-service, about 1 GB installed);
``--check``, ``--pairs``, ``--solve`` and ``--tamaas`` also ``mkl_fft`` (``pip install mkl_fft``: no dependency of
the package, measured and not adopted), ``--tamaas`` Tamaas (the ``test`` extra).

- ``--check``: ``mkl_fft.rfftn`` and ``irfftn`` of a random field against numpy.fft's on every grid of ``n0`` in
  2-399 (and a dozen larger) by ``n1`` in {n0, 40, 48, 64, 100, 2 n0}, both precisions, one thread; prints the
  grids where the largest error exceeds 1e-4 (float32) or 1e-10 (float64) of the largest value.
- ``--pairs``: the solver's float32 product (a dense load, the forward transform, the multiplier, the inverse)
  with its pyFFTW plans (the shipped wisdom's, in place; FFTW_ESTIMATE's, out of place, where it has none) and
  with MKL's transforms out of place in their stead (:func:`mkl_product_class`), CPU per pair, ``--rounds``
  rounds interleaved (the least is compared).
- ``--solve N``: the paper case (k_l = 16, k_s = 32, H = 0.8, seed 0, rms slope 0.1, 30 steps to p0/E* = 0.005,
  tol 1e-8) solved with the solver's products and with the MKL product in their place, ``--rounds`` times, the
  order alternating.
- ``--tamaas N``: Tamaas 2.9's ``PolonskyKeerRey`` on that case in fresh processes, alternately as installed and
  with ``mkl_fft`` imported first (``--tamaas-rounds`` each). mkl-service loads MKL with ``RTLD_GLOBAL``, so MKL's FFTW3
  interface then answers every FFTW call a library makes through the dynamic linker: the Tamaas wheel holds a
  static FFTW whose symbols it exports and binds lazily, so its transforms run on MKL (``MKL_VERBOSE=1`` lists
  them). pyFFTW's FFTW binds at load (``BIND_NOW``): loaded before MKL it keeps its own, loaded after, MKL's
  FFTW3 interface answers it (``core.fftw_library.pyfftw_library``).
- ``--on-mkl N``: the paper case solved by the package in fresh processes, alternately with ``ROUGHCONTACT_FFT=mkl``
  (MKL loaded before pyFFTW, so that it answers pyFFTW's calls) and ``pyfftw`` (``--rounds`` each);
  ``--on-mkl-scan``: pyFFTW's 2-D r2c and c2r on MKL against numpy.fft on the ``--check`` grids.

Run it single-threaded: ``OMP_NUM_THREADS=1 python benchmarks/fft_mkl.py --check --pairs 1024 2048 1000 2048x1024
--solve 1024 --tamaas 512 1024``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import roughcontact.core.backend as be  # noqa: E402
from roughcontact.core import fft as fft_module  # noqa: E402

HERE = Path(__file__).resolve().parent


def _version(name: str) -> str:
    try:
        return version(name)
    except PackageNotFoundError:
        return "(not installed)"


def _mkl_fft():
    try:
        import mkl_fft
    except ImportError:
        sys.exit("fft_mkl.py --check, --pairs, --solve and --tamaas need mkl_fft: pip install mkl_fft")
    return mkl_fft


class _Run:
    def __init__(self, fn):
        self.execute = fn


def mkl_product_class():
    """The solver's out-of-place product (``core.backend._FFTWProduct``) with MKL's transforms in its plans' stead."""
    mkl_fft = _mkl_fft()
    import pyfftw

    class MklProduct(be._FFTWProduct):
        def __init__(self, shape, dtype, in_place=False, threads=1):
            n0, n1 = shape
            self.spec = pyfftw.empty_aligned((n0, n1 // 2 + 1), dtype=np.result_type(dtype, np.complex64))
            self.in_place, self.n1, self.row, self.last = False, n1, n1, None
            self.input = pyfftw.zeros_aligned(shape, dtype=dtype)
            self.flat = self.input.reshape(-1)
            self.out = pyfftw.empty_aligned(shape, dtype=dtype)
            self.out_flat = self.out.reshape(-1)
            self.fwd = _Run(lambda: mkl_fft.rfftn(self.input, out=self.spec))
            self.bwd = _Run(lambda: mkl_fft.irfftn(self.spec, s=tuple(shape), out=self.out, norm="forward"))

    return MklProduct


def check() -> list:
    """The grids where mkl_fft's own transforms are off (module docstring), as ``(n0, n1, dtype, fwd, inv)``."""
    import mkl

    mkl_fft = _mkl_fft()

    before = mkl.set_num_threads_local(1)
    rng = np.random.default_rng(0)
    bad = []
    sizes = [*range(2, 400), 480, 500, 512, 600, 640, 720, 768, 800, 960, 1000, 1024, 1536, 2048]
    for n0 in sizes:
        for n1 in sorted({n0, 40, 48, 64, 100, 2 * n0 if n0 <= 1024 else n0}):
            x = rng.standard_normal((n0, n1))
            ref = np.fft.rfft2(x)
            for dt, tol in ((np.float32, 1e-4), (np.float64, 1e-10)):
                fwd = np.abs(mkl_fft.rfftn(x.astype(dt)) - ref).max() / np.abs(ref).max()
                inv = np.abs(mkl_fft.irfftn(ref.astype(np.result_type(dt, np.complex64)), s=(n0, n1)) - x).max()
                if fwd > tol or inv > tol * np.abs(x).max():
                    bad.append((n0, n1, np.dtype(dt).name, float(fwd), float(inv)))
    mkl.set_num_threads_local(before)
    print(f"check: {len(sizes)} sides n0; grids with a wrong transform: {len(bad)}")
    for n0, n1, dt, fwd, inv in bad:
        print(f"  n0 = {n0}, n1 = {n1}, {dt}: forward off by {fwd:.3g} of max |F|, inverse {inv:.3g}")
    return bad


def _shape(text: str) -> tuple[int, int]:
    a, _, b = text.partition("x")
    return int(a), int(b or a)


def pairs(shapes, rounds: int) -> None:
    mkl_product = mkl_product_class()
    rng = np.random.default_rng(0)
    for shape in shapes:
        shipped = fft_module.has_shipped_plans(shape)
        prods = {"pyfftw": be._FFTWProduct(shape, np.dtype(np.float32), shipped, 1),
                 "mkl": mkl_product(shape, np.dtype(np.float32))}
        x = rng.standard_normal(shape)
        mult = np.repeat((rng.random((shape[0], shape[1] // 2 + 1)) / (shape[0] * shape[1])).astype(np.float32)[
            ..., None], 2, axis=-1)
        cpu, outs = {k: [] for k in prods}, {}
        for _ in range(rounds):
            for name, p in prods.items():
                reps = max(3, int(2e7 // (shape[0] * shape[1])))
                c0 = time.process_time()
                for _ in range(reps):
                    p.load_dense(x, 1.0)
                    out = p.backward(p.forward(), mult)
                cpu[name].append((time.process_time() - c0) / reps * 1e3)
                outs[name] = np.array(out, dtype=np.float64)
        diff = np.abs(outs["mkl"] - outs["pyfftw"]).max() / np.abs(outs["pyfftw"]).max()
        print(f"pairs {shape[0]} x {shape[1]} (pyFFTW: {'shipped plans' if shipped else 'FFTW_ESTIMATE'}): "
              + ", ".join(f"{k} {' '.join(f'{v:.2f}' for v in vs)} ms" for k, vs in cpu.items())
              + f"; mkl / pyfftw (least) {min(cpu['mkl']) / min(cpu['pyfftw']):.3f}; outputs differ by {diff:.1e}",
              flush=True)


def _paper_case(n: int):
    from roughcontact.surfaces.synthetic import generate_surface

    return generate_surface(n, 16, 32, 0.8, 0, rms_slope=0.1), np.linspace(0.005 / 30, 0.005, 30)


def solve(n: int, rounds: int) -> None:
    from roughcontact.solver import solve_contact

    mkl_product = mkl_product_class()
    shared, plain = be.fftw_product, be._FFTWProduct

    def use(mkl: bool) -> None:
        shared.cache_clear()
        if mkl:  # every product of the solve (the shared small-grid ones and the larger grids' own)
            be.fftw_product = lambda shape, dtype, in_place, threads: mkl_product(shape, dtype)
            be._FFTWProduct = mkl_product
        else:
            be.fftw_product, be._FFTWProduct = shared, plain

    h, loads = _paper_case(n)
    for mkl in (False, True):  # warm-up: the process' one-off set-up (compiled kernels, units) outside the timing
        use(mkl)
        solve_contact(h, loads[:2], tol=1e-8)
    least = {}
    for r in range(rounds):
        for mkl in (False, True) if r % 2 == 0 else (True, False):
            use(mkl)
            c0, w0 = time.process_time(), time.perf_counter()
            ds = solve_contact(h, loads, tol=1e-8)
            c, w = time.process_time() - c0, time.perf_counter() - w0
            name = "mkl" if mkl else "pyfftw"
            least[name] = min(c, least.get(name, c))
            print(f"solve {n}^2 round {r} {name:6s}: CPU {c:.2f} s, wall {w:.2f} s, "
                  f"{int(ds.iterations.values.sum())} iterations, final A/A0 {ds.area_fraction.values[-1]:.6f}, "
                  f"converged {bool(ds.converged.values.all())}", flush=True)
    use(False)
    print(f"solve {n}^2: mkl / pyfftw, least CPU {least['mkl'] / least['pyfftw']:.3f}", flush=True)


_TAMAAS = """
import sys
sys.path.insert(0, {here!r})
if {mkl}:
    import mkl_fft  # noqa: F401  (MKL loaded with RTLD_GLOBAL by mkl-service)
import numpy as np
from bench_solver import run_tamaas
from fft_mkl import _paper_case
h, loads = _paper_case({n})
t = run_tamaas(h, loads, 1e-8)
print(f"{{t['cpu']:.2f}} {{t['wall']:.2f}} {{sum(t['iterations'])}} {{t['area'][-1]:.6f}}")
"""


def tamaas(n: int, rounds: int) -> None:
    least = {}
    for r in range(rounds):
        for mkl in (False, True) if r % 2 == 0 else (True, False):
            code = _TAMAAS.format(here=str(HERE), mkl=mkl, n=n)
            res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
            cpu, wall, its, area = res.stdout.split()[-4:]
            name = "with mkl_fft imported" if mkl else "as installed"
            least[name] = min(float(cpu), least.get(name, float(cpu)))
            print(f"tamaas {n}^2 round {r} {name}: CPU {cpu} s, wall {wall} s, {its} iterations, final A/A0 {area}",
                  flush=True)
    print(f"tamaas {n}^2: with mkl_fft imported / as installed, least CPU "
          f"{least['with mkl_fft imported'] / least['as installed']:.3f}", flush=True)


_ON_MKL = """
import sys, time
sys.path.insert(0, {here!r})
import numpy as np
from roughcontact.core.fftw_library import pyfftw_library
from roughcontact.solver import solve_contact
from fft_mkl import _paper_case
h, loads = _paper_case({n})
solve_contact(h, loads[:2], tol=1e-8)  # warm-up
c0, w0 = time.process_time(), time.perf_counter()
ds = solve_contact(h, loads, tol=1e-8)
c, w = time.process_time() - c0, time.perf_counter() - w0
print(pyfftw_library(), ds.attrs["fft_backend"], f"{{c:.2f}} {{w:.2f}}", int(ds.iterations.values.sum()),
      f"{{ds.area_fraction.values[-1]:.6f}}", bool(ds.converged.values.all()))
"""

_SCAN_ON_MKL = """
import mkl  # noqa: F401
import numpy as np, pyfftw
from roughcontact.core.fftw_library import pyfftw_library
assert pyfftw_library() == "mkl", pyfftw_library()
rng = np.random.default_rng(0)
bad, count = [], 0
for n0 in [*range(2, 400), 480, 500, 512, 600, 640, 720, 768, 800, 960, 1000, 1024, 1536, 2048]:
    for n1 in sorted({{n0, 40, 48, 64, 100, 2 * n0 if n0 <= 1024 else n0}}):
        x = rng.standard_normal((n0, n1))
        ref = np.fft.rfft2(x)
        for dt, tol in ((np.float32, 1e-4), (np.float64, 1e-10)):
            a = pyfftw.empty_aligned((n0, n1), dtype=dt)
            a[...] = x
            fwd = pyfftw.builders.rfft2(a, planner_effort="FFTW_ESTIMATE")
            b = pyfftw.empty_aligned(ref.shape, dtype=np.result_type(dt, np.complex64))
            b[...] = ref
            inv = pyfftw.builders.irfft2(b, s=(n0, n1), planner_effort="FFTW_ESTIMATE")
            e1 = np.abs(fwd() - ref).max() / np.abs(ref).max()
            e2 = np.abs(inv() - x).max() / np.abs(x).max()
            count += 1
            if e1 > tol or e2 > tol:
                bad.append((n0, n1, np.dtype(dt).name, float(e1), float(e2)))
print(count, bad)
"""


def on_mkl(sizes, rounds: int, scan: bool) -> None:
    """The package with ``ROUGHCONTACT_FFT=mkl`` (MKL's FFTW3 interface answers pyFFTW) against pyFFTW's FFTW, in
    fresh processes; the scan with mkl-service imported first."""
    if scan:
        res = subprocess.run([sys.executable, "-c", _SCAN_ON_MKL.format()], capture_output=True, text=True,
                             check=True)
        count, _, bad = res.stdout.strip().partition(" ")
        print(f"pyFFTW on MKL, rfft2 and irfft2 against numpy.fft: {count} grid and precision pairs, wrong: {bad}",
              flush=True)
    for n in sizes:
        least = {}
        for r in range(rounds):
            for mkl in (False, True) if r % 2 == 0 else (True, False):
                code = _ON_MKL.format(here=str(HERE), n=n)
                env = {**os.environ, "ROUGHCONTACT_FFT": "mkl" if mkl else "pyfftw"}
                res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
                lib, label, cpu, wall, its, area, conv = res.stdout.split()[-7:]
                least[lib] = min(float(cpu), least.get(lib, float(cpu)))
                print(f"pyfftw on {lib:4s} {n}^2 round {r}: fft_backend {label}, CPU {cpu} s, wall {wall} s, {its} "
                      f"iterations, final A/A0 {area}, converged {conv}", flush=True)
        print(f"pyfftw {n}^2: on mkl / on fftw, least CPU {least['mkl'] / least['fftw']:.3f}", flush=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--pairs", nargs="*", default=[], metavar="N0xN1")
    ap.add_argument("--solve", type=int, nargs="*", default=[], metavar="N")
    ap.add_argument("--tamaas", type=int, nargs="*", default=[], metavar="N")
    ap.add_argument("--on-mkl", type=int, nargs="*", default=[], metavar="N",
                    help="the paper case with ROUGHCONTACT_FFT=mkl against pyFFTW's FFTW")
    ap.add_argument("--on-mkl-scan", action="store_true", help="pyFFTW's 2-D transforms on MKL against numpy.fft")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--tamaas-rounds", type=int, default=None, help="rounds of --tamaas (default: --rounds)")
    args = ap.parse_args(argv)
    if args.check or args.pairs or args.solve or args.tamaas:
        _mkl_fft()
    print(f"{time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime())}, load {os.getloadavg()[0]:.2f}, "
          + ", ".join(f"{name} {_version(name)}" for name in ("mkl", "mkl_fft", "pyFFTW", "tamaas"))
          + f", CPU {fft_module.machine_key()}, OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS')}", flush=True)
    if args.check:
        check()
    if args.pairs:
        pairs([_shape(s) for s in args.pairs], args.rounds)
    for n in args.solve:
        solve(n, args.rounds)
    if args.on_mkl or args.on_mkl_scan:
        on_mkl(args.on_mkl, args.rounds, args.on_mkl_scan)
    for n in args.tamaas:
        tamaas(n, args.tamaas_rounds or args.rounds)
    print(f"end {time.strftime('%H:%M:%S UTC', time.gmtime())}, load {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()

"""The paper case with the FFTW that pyFFTW loads, every plan measured in this process, beside Tamaas (issue 63).

``python benchmarks/fftw_simd.py [--n 1024] [--repeats 2] [--no-tamaas] [--patient]`` solves the paper case (k_l = 16,
k_s = 32, H = 0.8, rms slope 0.1, 30 equal steps to p0/E* = 0.005) with :func:`~roughcontact.solver.solve_contact`
after a warm-up solve, then Tamaas' ``PolonskyKeerRey`` once, in the same process, single-threaded, and prints
the FFTW library pyFFTW loaded, the SIMD extensions FFTW says it was built with (``fftwf_version``), the CPU of
each solve and Tamaas' CPU over the least of ours, under the times it started and ended. One thread unless
``OMP_NUM_THREADS`` says otherwise (it is set to 1 where unset).

Every plan is made with ``FFTW_MEASURE`` (``--patient``: ``FFTW_PATIENT``) in the process (the warm-up solve
measures them, the timed ones reuse them from FFTW's store), not from the shipped wisdom: the shipped plans name the
codelets of pyFFTW's wheel, which another FFTW build lacks (FFTW then forgets the whole store and plans by its
heuristics). So the script compares two FFTW builds on an equal footing: run it once as installed, once with
``PYTHONPATH`` pointing at a copy of pyFFTW whose float library is another build (benchmarks/README.md, "The weak
scaling's serial reference; an FFTW with AVX2 and AVX-512 codelets"). The outputs are not the shipped plans' bits.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import datetime
import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402


def fftw_float_library() -> tuple[str, str]:
    """``(path, version)`` of the single-precision FFTW this process loaded (after a pyFFTW transform)."""
    with open("/proc/self/maps") as f:
        paths = sorted({line.split()[-1] for line in f if "libfftw3f" in line and "_omp" not in line
                        and line.split()[-1].startswith("/")})
    if not paths:
        return "(not loaded)", ""
    version = (ctypes.c_char * 128).in_dll(ctypes.CDLL(paths[0]), "fftwf_version").value.decode()
    return paths[0], version


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=1024)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--no-tamaas", action="store_true")
    ap.add_argument("--patient", action="store_true", help="plan with FFTW_PATIENT instead of FFTW_MEASURE")
    a = ap.parse_args(argv)
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from bench_solver import run_tamaas

    from roughcontact.core import fft
    from roughcontact.solver import solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    start = datetime.datetime.now(datetime.UTC)
    flags = ("FFTW_PATIENT",) if a.patient else ("FFTW_MEASURE",)
    fft.PLANNER_FLAGS = flags  # measured here, not the shipped wisdom (module docstring)
    fft.shipped_wisdom_only = contextlib.nullcontext
    load0 = os.getloadavg()
    h = generate_surface(a.n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(0.005 / 30, 0.005, 30)
    solve_contact(h, loads)  # warm-up: the plans measured
    cpu = []
    for _ in range(a.repeats):
        c0 = time.process_time()
        ds = solve_contact(h, loads)
        cpu.append(time.process_time() - c0)
    path, version = fftw_float_library()
    tamaas = None if a.no_tamaas else run_tamaas(h, loads, 1e-8)
    load1 = os.getloadavg()
    print(f"fftw_simd {start:%Y-%m-%d %H:%M}-{datetime.datetime.now(datetime.UTC):%H:%M} UTC, N = {a.n}, plans "
          f"{flags[0]}, load {load0[0]:.2f} -> {load1[0]:.2f}")
    print(f"float FFTW: {path} ({version})")
    print(f"single solve CPU [s]: {' '.join(f'{c:.2f}' for c in cpu)}; iterations {int(ds.iterations.sum())}, "
          f"converged {bool(ds.converged.all())}, A/A0 last step {float(ds.area_fraction[-1]):.6f}")
    if tamaas is not None:
        print(f"tamaas CPU {tamaas['cpu']:.2f} s, iterations {int(sum(tamaas['iterations']))}, A/A0 last step "
              f"{tamaas['area'][-1]:.6f}; Tamaas / least of ours {tamaas['cpu'] / min(cpu):.1f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

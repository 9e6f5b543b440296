"""Which library answers pyFFTW's calls, and ``ROUGHCONTACT_FFT=mkl``: Intel MKL's FFTW3 interface under pyFFTW.

pyFFTW ships its own FFTW, and its extension binds FFTW's functions when it loads, looking in the process'
global namespace first. Where Intel MKL's runtime is there already (loaded with ``RTLD_GLOBAL``, as mkl-service's
``import mkl`` does), MKL's FFTW3 interface answers pyFFTW's double and single-precision calls instead of FFTW:
the same plans asked for, MKL's transforms done, no wisdom kept (the shipped FFTW plans do not apply), results
different from FFTW's in the last bits. :func:`pyfftw_library` tells which answers, and the outputs' ``fft_backend``
says it (:func:`fft_label`: ``pyfftw-mkl``), whoever loaded MKL.

``ROUGHCONTACT_FFT=mkl`` asks for it: :mod:`.fft` then loads MKL (:func:`load_mkl_first`, mkl-service from the
``mkl`` extra: ``pip install -e '.[mkl]'``, about 1 GB installed) before it imports pyFFTW. Measured on an Intel
Xeon (2026-12-05, benchmarks/README.md, "Intel MKL's FFTs"): the paper case at 256²-1024² in 0.66-0.68x the CPU, the
same iterations and A/A0, and pyFFTW's 2-D r2c and c2r on MKL within 1e-4 (float32) and 1e-10 (float64) of
numpy.fft's largest value on 4912 grids and precisions. MKL is loaded for the whole process: any other library that
binds FFTW's functions lazily after that (Tamaas 2.9's wheel, whose FFTW is static and exported) runs on MKL too
(Tamaas took 0.30-0.34x its CPU). The variable must be set before the process first imports pyFFTW; the solve
refuses it otherwise. MKL's FFTW3 interface plans no 1-D transform batched over two axes (the MPI slabs'
``(B, rows, n)`` along ``n``: pyFFTW raises "the planner returning NULL"), but plans the same transform on a
``(B rows, n)`` view, batched over one: :func:`one_batch_axis` gives the array to plan on.

Examples
--------
>>> from roughcontact.core.fftw_library import fft_label, pyfftw_library
>>> pyfftw_library() in ("fftw", "mkl", "other", "none")
True
>>> fft_label("numpy")
'numpy'
"""

from __future__ import annotations

import ctypes
import functools
import importlib
import importlib.util
import logging
import os

import numpy as np

#: What to install for ``ROUGHCONTACT_FFT=mkl``.
INSTALL_HINT = "pip install -e '.[mkl]' (mkl-service, which brings Intel MKL)"

_load_error: str | None = None


def mkl_installed() -> bool:
    """Whether mkl-service is installed, found without importing it: an import would load MKL into the process'
    global namespace, under every library that binds FFTW's functions afterwards (module docstring)."""
    return importlib.util.find_spec("mkl") is not None


def requested() -> bool:
    """Whether ``ROUGHCONTACT_FFT=mkl`` is set."""
    return os.environ.get("ROUGHCONTACT_FFT", "").strip().lower() == "mkl"


def load_mkl_first() -> None:
    """Where :func:`requested`, load MKL's runtime into the global namespace (``import mkl``), so that MKL answers
    pyFFTW once it loads (where pyFFTW was loaded before, :func:`check_request` refuses the request). A failure
    to load is kept for :func:`check_request` to name."""
    global _load_error
    if not requested():
        return
    try:
        importlib.import_module("mkl")
    except ImportError as err:
        _load_error = str(err)


def _global_symbol(name: str) -> bool:
    try:
        getattr(ctypes.CDLL(None), name)
    except (AttributeError, OSError, TypeError):  # TypeError: no process handle (Windows)
        return False
    return True


@functools.cache
def pyfftw_library() -> str:
    """The library that answers pyFFTW's double and single-precision calls in this process.

    ``"fftw"``: the FFTW pyFFTW ships (the shipped wisdom's plans are for it); ``"mkl"``: Intel MKL's FFTW3
    interface (module docstring); ``"other"``: another FFTW3 implementation; ``"none"``: no pyFFTW. Fixed when
    pyFFTW loads, so cached. FFTW exports its wisdom under a ``(fftw-3...`` header whatever it holds; MKL keeps
    none and exports empty strings.
    """
    try:
        import pyfftw
    except ImportError:
        return "none"
    if all(w.startswith(b"(fftw-") for w in pyfftw.export_wisdom()[:2]):
        return "fftw"
    library = "mkl" if _global_symbol("DftiCreateDescriptor") else "other"
    if not requested():
        logging.getLogger(__name__).warning(
            "pyFFTW's transforms are answered by %s, loaded into the process before pyFFTW (not by pyFFTW's FFTW); "
            "the shipped FFTW plans do not apply; the outputs say fft_backend='pyfftw-%s'",
            "Intel MKL's FFTW3 interface" if library == "mkl" else "another FFTW3 library", library)
    return library


def fft_label(name: str) -> str:
    """The outputs' ``fft_backend`` for transforms of the FFT backend ``name``: ``"pyfftw-mkl"`` (or
    ``"pyfftw-other"``) where :func:`pyfftw_library` is not pyFFTW's FFTW, else ``name``."""
    if name == "pyfftw" and pyfftw_library() not in ("fftw", "none"):
        return f"pyfftw-{pyfftw_library()}"
    return name


def one_batch_axis(a):
    """The array to plan a 1-D transform along ``a``'s last axis on: where MKL answers pyFFTW, a view of ``a``
    (``(..., n)``, its leading axes mergeable without a copy) with one batch axis, ``(-1, n)``; else ``a`` itself.

    Raises ``ValueError`` where the view would need a copy (a transform planned on a copy would not write ``a``).
    """
    if pyfftw_library() != "mkl" or a.ndim <= 2:
        return a
    view = a.reshape(-1, a.shape[-1])
    if not np.shares_memory(view, a):
        raise ValueError(f"one_batch_axis: an array of shape {a.shape} and strides {a.strides} has no view "
                         "with one batch axis")
    return view


def check_request() -> None:
    """A ``ValueError`` naming the remedy where ``ROUGHCONTACT_FFT=mkl`` cannot be honoured."""
    if _load_error is not None:
        raise ValueError(f"ROUGHCONTACT_FFT=mkl, but Intel MKL cannot be loaded ({_load_error}): install it "
                         f"({INSTALL_HINT}) or unset ROUGHCONTACT_FFT")
    library = pyfftw_library()
    if library == "none":
        raise ValueError("ROUGHCONTACT_FFT=mkl runs MKL under pyFFTW, which cannot be imported: pip install pyfftw")
    if library != "mkl":
        raise ValueError("ROUGHCONTACT_FFT=mkl takes effect only where it is set before the process first imports "
                         f"pyFFTW; here pyFFTW's own FFTW answers ({library}): set it in the environment before "
                         "starting Python, or unset it")

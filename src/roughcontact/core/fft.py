"""Real 2-D FFT pairs with cached plans: pyFFTW when importable, numpy.fft otherwise.

All transforms use numpy's conventions: the forward transform is unnormalised, the
backward transform divides by ``n0 * n1``. Arrays are ``float64`` of shape ``(n0, n1)``
in real space and ``complex128`` of shape ``(n0, n1 // 2 + 1)`` in Fourier space;
``dtype=numpy.float32`` gives single-precision pairs (``float32`` / ``complex64``, about
half the time of a double pair; the solver uses them for its inner products only).

Reproducibility: FFTW plans are made with ``FFTW_ESTIMATE`` (:data:`PLANNER_FLAGS`),
which never times anything, so the same transform gives the same bits in every process
on a given machine and build. ``FFTW_MEASURE`` would time candidate plans and, on a
loaded machine, pick different ones in different processes, whose results differ in the
last bits. ESTIMATE's heuristics are slow for some shapes, though (a float32 pair at
N = 1024 took 1.8x the measured plan's time), so the package ships *wisdom*: plans
measured once (with ``FFTW_PATIENT``, :data:`WISDOM_FLAGS`) for square grids of 32 to 8192
points per side, both precisions, one thread (:data:`WISDOM_FILE`, made by :func:`write_wisdom`). Every pair
is planned with the shipped wisdom alone (any other wisdom in the process is set aside
and restored afterwards), and FFTW uses wisdom of a more patient planner for an
``FFTW_ESTIMATE`` request: the plan is then a function of the shipped file alone,
whatever the machine's load. Where the shipped plans cannot be used (another FFTW
version, a CPU without the SIMD they name), FFTW falls back to its ``FFTW_ESTIMATE``
heuristics, again the same in every process. The MPI solver's 1-D slab transforms have
plans of their own in the same sets (:func:`add_plans`, from
:func:`roughcontact.solver.mpi.slabs.write_wisdom`; ``FFTW_MEASURE``).

The best plan depends on the processor (plans measured on a Xeon cost 1.4x the measured
plans' time for a float32 pair at N = 1024 on an AMD EPYC, 2026-11-26), so the file holds one
set of plans per processor model (:func:`machine_key`, the CPU's model name) and a default
for any other model: the plan is a function of the file and the processor model.
"""

from __future__ import annotations

import contextlib
import functools
import json
import logging
import os
import time
from pathlib import Path

import numpy as np

from . import fftw_library as _library
from .cell import Cell

_library.load_mkl_first()  # ROUGHCONTACT_FFT=mkl: MKL's FFTW3 interface to answer pyFFTW (core.fftw_library)

try:  # pragma: no cover - exercised by whichever backend is installed
    import pyfftw

    _HAVE_PYFFTW = True
except ImportError:  # pragma: no cover
    pyfftw = None
    _HAVE_PYFFTW = False

_log = logging.getLogger(__name__)

#: Backends a caller may ask for (``ROUGHCONTACT_FFT=mkl``: pyFFTW answered by Intel MKL, core.fftw_library).
BACKENDS = ("pyfftw", "numpy", "mkl")

#: FFTW planner flags. ``FFTW_ESTIMATE`` is deterministic (no timing); do not use
#: ``FFTW_MEASURE``/``FFTW_PATIENT`` here: they make results vary between processes.
PLANNER_FLAGS = ("FFTW_ESTIMATE",)


#: Plans measured once and shipped with the package (module docstring).
WISDOM_FILE = Path(__file__).with_name("fftw_wisdom.json")
#: Planner flags :func:`write_wisdom` measures with. FFTW_PATIENT's plans took 0.80-0.99x the
#: time of FFTW_MEASURE's for a pair at N = 256-4096, both precisions, in and out of place (AMD
#: EPYC, 2026-11-27, interleaved; 0.81 for the solver's float32 pair at 1024); FFTW_EXHAUSTIVE's
#: were no faster at 1024 and took 11x longer to plan. On an Intel Xeon (the default set, N <= 2048,
#: 2026-12-03) against the former default set (the Xeon's MEASURE plans, its in-place pairs the
#: EPYC's): 0.84x for that pair, 0.93x out of place, the paper case 0.82x the CPU at 1024
#: (docs/solver.md).
WISDOM_FLAGS = ("FFTW_PATIENT",)
#: Sides above which :func:`write_wisdom` measures with FFTW_MEASURE whatever its flags: FFTW_PATIENT
#: took 21 min of one core for the 4096 pairs (256 s for 2048; 772 s on the Intel Xeon), and would
#: take hours for 8192.
WISDOM_PATIENT_MAX = 4096
#: Square grid sizes whose plans :func:`write_wisdom` measures.
WISDOM_SIZES = (32, 64, 128, 256, 512, 1024, 2048, 4096, 8192)


#: Precisions of an FFTW wisdom export, in pyFFTW's order.
_PRECISIONS = ("double", "single", "long_double")


def machine_key() -> str:
    """The processor model this process runs on (``model name`` of /proc/cpuinfo), "" if unknown."""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return ""


def _machines(data: dict) -> dict:
    """``{model: {precision: wisdom}}`` of a wisdom file (one unnamed set in the first format)."""
    if "machines" in data:
        return data["machines"]
    return {data.get("machine", ""): {k: data[k] for k in _PRECISIONS}}


@functools.lru_cache(maxsize=1)
def shipped_wisdom() -> tuple[bytes, bytes, bytes] | None:
    """The shipped FFTW wisdom for this processor model (double, single, long double), or None.

    The plans measured on this model when the file has them, else the file's default set.
    """
    try:
        data = json.loads(WISDOM_FILE.read_text())
    except FileNotFoundError:
        return None
    machines = _machines(data)
    chosen = machines.get(machine_key()) or machines[data.get("default", next(iter(machines)))]
    return tuple(chosen[k].encode("ascii") for k in _PRECISIONS)


def has_pyfftw() -> bool:
    """Whether pyFFTW imports here (else the transforms are numpy's or SciPy's)."""
    return _HAVE_PYFFTW


def has_shipped_plans(shape) -> bool:
    """Whether the shipped wisdom holds measured plans for ``shape`` (square, :data:`WISDOM_SIZES`)."""
    n0, n1 = (int(n) for n in shape)
    return n0 == n1 and n0 in WISDOM_SIZES and shipped_wisdom() is not None


@contextlib.contextmanager
def shipped_wisdom_only():
    """Plan inside this block with the shipped wisdom alone (module docstring).

    FFTW reuses wisdom from a more patient planner: a plan timed with FFTW_MEASURE
    earlier in this process (by any pyFFTW user) would replace the deterministic
    choice, so the store is emptied and given the shipped plans for the block. The
    caller's wisdom is put back afterwards: this package must not erase the plans
    another pyFFTW user in the same process has measured or imported.
    """
    saved = pyfftw.export_wisdom()
    pyfftw.forget_wisdom()
    wisdom = shipped_wisdom()
    if wisdom is not None:
        pyfftw.import_wisdom(wisdom)
    try:
        yield
    finally:
        pyfftw.forget_wisdom()
        pyfftw.import_wisdom(saved)


def write_wisdom(path: str | os.PathLike = WISDOM_FILE, sizes=WISDOM_SIZES, flags=WISDOM_FLAGS,
                 keep: bool = False) -> Path:
    """Measure single-threaded plans for ``n x n`` pairs of both precisions; add them to ``path``.

    Run once per FFTW build and processor model (``python -c "from roughcontact.core.fft import
    write_wisdom; write_wisdom()"``), on a quiet machine; the plans are filed under this
    processor's :func:`machine_key`, beside those of other models already in the file (a file
    of another FFTW version or sizes is started afresh; its default set stays the first model's).
    Sides above :data:`WISDOM_PATIENT_MAX` are measured with FFTW_MEASURE; each set records the
    flags asked for at each side (``"flags": {"1024": ["FFTW_PATIENT"], ...}``).
    ``keep=True`` starts from this model's plans in the file, so that only the problems they lack
    are measured (the others keep their plans, bit for bit); the default set then gains this
    model's plans for the problems it lacks (:func:`_fill_missing`).
    """
    from .files import write_text_atomic

    try:
        old = json.loads(Path(path).read_text())
    except FileNotFoundError:
        old = {}
    pyfftw.forget_wisdom()
    mine = _machines(old).get(machine_key()) if keep and old else None
    if mine:
        pyfftw.import_wisdom(tuple(mine[k].encode("ascii") for k in _PRECISIONS))
    asked = {}
    for n in sizes:
        flags_n = asked[str(n)] = tuple(flags) if n <= WISDOM_PATIENT_MAX else ("FFTW_MEASURE",)
        start = time.process_time()
        for real, cplx in ((np.float64, np.complex128), (np.float32, np.complex64)):
            # the same arrays (shapes, alignment, out of place) as RealFFT2 plans
            a, a_out = (pyfftw.empty_aligned((n, n), dtype=real) for _ in range(2))
            b, b_in = (pyfftw.empty_aligned((n, n // 2 + 1), dtype=cplx) for _ in range(2))
            pyfftw.FFTW(a, b, axes=(0, 1), direction="FFTW_FORWARD", flags=flags_n, threads=1)
            pyfftw.FFTW(b_in, a_out, axes=(0, 1), direction="FFTW_BACKWARD", flags=flags_n, threads=1)
            # the solver's SpectralProduct pair of this precision, in place (core.backend._FFTWProduct)
            c = pyfftw.empty_aligned((n, n // 2 + 1), dtype=cplx)
            r = c.view(real)[:, :n]
            pyfftw.FFTW(r, c, axes=(0, 1), direction="FFTW_FORWARD", flags=flags_n, threads=1)
            pyfftw.FFTW(c, r, axes=(0, 1), direction="FFTW_BACKWARD", flags=flags_n, threads=1)
        _log.info("planned the %d x %d pairs with %s in %.0f s of CPU", n, n, "|".join(flags_n),
                  time.process_time() - start)
    measured = dict(zip(_PRECISIONS, (w.decode("ascii") for w in pyfftw.export_wisdom()), strict=True))
    measured["flags"] = {n: list(f) for n, f in asked.items()}
    out = Path(path)
    head = {"sizes": list(sizes), "fftw": pyfftw.__version__}
    same = old and all(old.get(k) == v for k, v in head.items())
    # a file of the first format names its flags once, for every side of every set it holds
    once = {str(n): old.get("flags", []) for n in sizes}
    machines = {m: {"flags": once, **w} for m, w in _machines(old).items()} if same else {}
    key = machine_key()
    machines[key] = measured
    default = old.get("default", next(iter(machines))) if same else key
    if keep and default != key:
        filled = {k: _fill_missing(machines[default][k], measured[k]) for k in _PRECISIONS}
        machines[default] = {**machines[default], **filled}
    text = json.dumps({**head, "default": default, "machines": machines}, indent=1)
    write_text_atomic(out, text + "\n")
    shipped_wisdom.cache_clear()
    return out


def add_plans(problems, path: str | os.PathLike = WISDOM_FILE, record: dict | None = None,
              flags=("FFTW_MEASURE",)) -> Path:
    """Measure the plans of ``problems`` and add them to the set of ``path`` this processor plans with.

    For transforms other than :func:`write_wisdom`'s square pairs (the MPI solver's slabs:
    :func:`roughcontact.solver.mpi.slabs.write_wisdom`). ``problems`` are callables ``plan(flags)``,
    each making the plans of one problem with ``flags``. They are measured (``flags``) in an empty
    store: the set's own plans stay as they were, line for line, and the measured entries for
    problems the set lacks are appended (:func:`_fill_missing`). Where the set names another solver
    for a problem that a measured plan also solved, it is kept too, unless FFTW then rejects the set
    for one of ``problems`` (an entry it cannot apply: FFTW then forgets the whole store and plans by
    its heuristics): such entries are replaced by the measured ones, one at a time, in the set's order,
    each only if fewer problems are then rejected. ``record`` (a dict) is merged into the set, to say
    what was planned. The set is this processor's (:func:`machine_key`) where the file has one, else
    its default; the caller's wisdom is put back afterwards.

    Raises
    ------
    ValueError
        For a file of the first format (one unnamed set): write it again with :func:`write_wisdom`.
    """
    from .files import write_text_atomic

    data = json.loads(Path(path).read_text())
    if "machines" not in data:
        raise ValueError(f"{path}: a wisdom file of the first format (one unnamed set); write it again with "
                         "write_wisdom() before adding plans to it")
    machines = data["machines"]
    key = machine_key() if machine_key() in machines else data.get("default", next(iter(machines)))
    chosen = machines[key]
    saved = pyfftw.export_wisdom()
    try:
        pyfftw.forget_wisdom()
        for plan in problems:
            plan(tuple(flags))
        measured = [w.decode("ascii") for w in pyfftw.export_wisdom()]
        base = [chosen[k] for k in _PRECISIONS]
        by_key = [_entries_by_key(theirs) for theirs in measured]
        clashes = [(i, _entry_key(line)) for i, mine in enumerate(base) for line in _entries(mine)
                   if by_key[i].get(_entry_key(line), line.strip()) != line.strip()]
        replace: set = set()
        rejected = _rejected(_merged(base, measured, replace), problems)
        for clash in clashes:
            if not rejected:
                break
            fewer = _rejected(_merged(base, measured, replace | {clash}), problems)
            if fewer < rejected:
                replace, rejected = replace | {clash}, fewer
    finally:
        pyfftw.forget_wisdom()
        pyfftw.import_wisdom(saved)
    if rejected:
        _log.warning("FFTW still rejects the composed wisdom for %d of %d problems", rejected, len(problems))
    chosen.update(zip(_PRECISIONS, _merged(base, measured, replace), strict=True))
    chosen.update(record or {})
    write_text_atomic(Path(path), json.dumps(data, indent=1) + "\n")
    shipped_wisdom.cache_clear()
    return Path(path)


def _entries(wisdom: str) -> list[str]:
    """The entry lines of FFTW's text export ``wisdom`` (one ``(solver reg flags flags slvndx md5 x4)`` each)."""
    return [line for line in wisdom.splitlines()[1:] if line.strip().startswith("(")]


def _entry_key(line: str) -> tuple[str, ...]:
    """The problem an entry line solves: its planner flags and the problem's md5 (the last four words)."""
    words = line.strip().rstrip(")").split()
    return (*words[2:4], *words[-4:])


def _entries_by_key(wisdom: str) -> dict:
    return {_entry_key(line): line.strip() for line in _entries(wisdom)}


def _merged(base, measured, replace) -> tuple[str, ...]:
    """Each precision's ``base`` with its entries keyed ``(precision, key)`` in ``replace`` taken from
    ``measured``, then ``measured``'s entries for the problems it lacks appended."""
    out = []
    for i, (mine, theirs) in enumerate(zip(base, measured, strict=True)):
        by_key = _entries_by_key(theirs)
        lines = [("  " + by_key[_entry_key(line)]) if line.strip().startswith("(")
                 and (i, _entry_key(line)) in replace else line for line in mine.rstrip().splitlines()]
        out.append(_fill_missing("\n".join(lines) + "\n", theirs))
    return tuple(out)


def _rejected(wisdom, problems) -> int:
    """How many of ``problems`` FFTW plans otherwise than from ``wisdom`` alone (the store gains entries)."""
    count = 0
    for plan in problems:
        pyfftw.forget_wisdom()
        pyfftw.import_wisdom(tuple(w.encode("ascii") for w in wisdom))
        before = pyfftw.export_wisdom()
        plan(tuple(PLANNER_FLAGS))
        count += pyfftw.export_wisdom() != before
    return count


def _fill_missing(wisdom: str, extra: str) -> str:
    """``wisdom`` (FFTW's text export) with the entries of ``extra`` for problems it has no plan for.

    An entry is one line ``(solver reg flags flags slvndx md5 md5 md5 md5)``; its problem is the
    last four words with the flags.
    """
    have = {_entry_key(line) for line in _entries(wisdom)}
    new = [line for line in _entries(extra) if _entry_key(line) not in have]
    if not new:
        return wisdom
    body = wisdom.rstrip()[:-1].rstrip()  # the export's closing parenthesis comes back last
    return "\n".join([body, *new, ")"]) + "\n"


def default_backend() -> str:
    """Name of the backend used when none is asked for.

    ``ROUGHCONTACT_FFT=numpy`` in the environment forces the numpy.fft fallback (no FFTW anywhere: the single
    solve, a batch, the MPI ranks); ``ROUGHCONTACT_FFT=mkl`` gives ``"pyfftw"`` with Intel MKL answering pyFFTW's
    calls (:mod:`.fftw_library`; a ``ValueError`` naming the remedy where it cannot).
    """
    forced = os.environ.get("ROUGHCONTACT_FFT", "").strip().lower()
    if forced:
        if forced not in BACKENDS:
            raise ValueError(
                f"ROUGHCONTACT_FFT={forced!r} is not a known FFT backend; allowed: {', '.join(BACKENDS)}"
            )
        if forced == "pyfftw" and not _HAVE_PYFFTW:
            raise ValueError("ROUGHCONTACT_FFT=pyfftw but pyfftw cannot be imported")
        if forced == "mkl":
            _library.check_request()
            return "pyfftw"
        return forced
    return "pyfftw" if _HAVE_PYFFTW else "numpy"


class RealFFT2:
    """A planned real-to-complex / complex-to-real 2-D transform pair for one shape.

    Parameters
    ----------
    shape : (int, int)
        Real-space shape ``(n0, n1)``; ``(n, 1)`` is a profile's grid (a 1-D transform along axis 0).
    threads : int
        Threads FFTW may use (numpy's pocketfft is single-threaded here).
    backend : {"pyfftw", "numpy"} or None
        ``None`` picks :func:`default_backend`.
    dtype : numpy.float64 or numpy.float32
        Precision of the transforms (real ``dtype``, complex of the same precision).

    Notes
    -----
    ``forward`` and ``backward`` return views of internal buffers that the next call
    overwrites: copy the result if it must outlive the next transform. This is what
    makes the solver's inner loop allocation-free.
    """

    def __init__(self, shape: tuple[int, int], threads: int = 1, backend: str | None = None,
                 dtype=np.float64):
        n0, n1 = (int(s) for s in shape)
        if n0 < 2 or n1 < 1 or (n1 == 1 and n0 < 4):  # (n, 1): a profile's one-row grid (Cell.profile)
            raise ValueError(f"FFT shape must be at least 2x2, or (n, 1) with n >= 4 for a profile, got {shape}")
        self.shape = (n0, n1)
        self.spectral_shape = (n0, n1 // 2 + 1)
        self.backend = backend or default_backend()
        if self.backend not in BACKENDS:
            raise ValueError(f"FFT backend {self.backend!r} unknown; allowed: {', '.join(BACKENDS)}")
        self.threads = max(1, int(threads))
        self.dtype = np.dtype(dtype)
        if self.dtype not in (np.dtype(np.float64), np.dtype(np.float32)):
            raise ValueError(f"FFT dtype must be float64 or float32, got {self.dtype}")
        cdtype = np.result_type(self.dtype, np.complex64)
        if self.backend == "pyfftw":
            if not _HAVE_PYFFTW:
                raise ValueError("pyfftw backend requested but pyfftw cannot be imported")
            self._real = pyfftw.empty_aligned(self.shape, dtype=self.dtype)
            self._spec = pyfftw.empty_aligned(self.spectral_shape, dtype=cdtype)
            self._spec_in = pyfftw.empty_aligned(self.spectral_shape, dtype=cdtype)
            self._real_out = pyfftw.empty_aligned(self.shape, dtype=self.dtype)
            flags = tuple(PLANNER_FLAGS)
            with shipped_wisdom_only():
                self._fwd = pyfftw.FFTW(
                    self._real, self._spec, axes=(0, 1), direction="FFTW_FORWARD",
                    flags=flags, threads=self.threads,
                )
                self._bwd = pyfftw.FFTW(
                    self._spec_in, self._real_out, axes=(0, 1), direction="FFTW_BACKWARD",
                    flags=flags, threads=self.threads,
                )

    def forward(self, a: np.ndarray) -> np.ndarray:
        """rfft2 of real ``a`` (n0, n1) -> complex (n0, n1//2+1), unnormalised."""
        if self.backend == "numpy":
            return np.fft.rfft2(np.asarray(a, dtype=self.dtype))
        self._real[...] = a
        self._fwd.execute()
        return self._spec

    def backward(self, a_hat: np.ndarray) -> np.ndarray:
        """irfft2 of complex ``a_hat`` (n0, n1//2+1) -> real (n0, n1), divided by n0*n1."""
        if self.backend == "numpy":
            return np.fft.irfft2(a_hat, s=self.shape).astype(self.dtype, copy=False)
        # c2r transforms destroy their input, so FFTW always works on our copy.
        self._spec_in[...] = a_hat
        self._bwd.execute()
        self._real_out *= self.dtype.type(1.0 / (self.shape[0] * self.shape[1]))
        return self._real_out


@functools.lru_cache(maxsize=32)
def _cached_fft(shape: tuple[int, int], threads: int, backend: str, dtype: str = "float64") -> RealFFT2:
    return RealFFT2(shape, threads=threads, backend=backend, dtype=np.dtype(dtype))


def get_fft(shape: tuple[int, int], threads: int = 1, backend: str | None = None,
            dtype=np.float64) -> RealFFT2:
    """Cached :class:`RealFFT2` for ``shape``: plans are made once per shape and reused.

    The cache key is normalised (shape as ints, threads >= 1, the resolved backend name,
    the dtype's name), so every caller asking for the same transform shares one set of
    plans and buffers. A ``float64`` pair is keyed exactly as before single-precision
    pairs existed.
    """
    key = (tuple(int(s) for s in shape), max(1, int(threads)), backend or default_backend())
    name = np.dtype(dtype).name
    if name == "float64":
        return _cached_fft(*key)
    return _cached_fft(*key, name)


def wavenumbers(shape, length=1.0) -> tuple[np.ndarray, np.ndarray]:
    """Wavenumbers of the rfft2 grid of a periodic ``nx x ny`` domain of sides ``Lx x Ly``.

    Parameters
    ----------
    shape : int or (int, int)
        Grid points ``(nx, ny)`` along axis 0 (x) and axis 1 (y); an int ``n`` means ``(n, n)``.
    length : float or (float, float)
        Sides ``(Lx, Ly)`` of the domain [length]; a float ``L`` means ``(L, L)``.

    Returns
    -------
    (kx, ky) : numpy.ndarray, float64, shapes (nx, 1) and (1, ny//2+1)
        Broadcastable to ``(nx, ny//2+1)``: ``kx = mx / Lx`` along axis 0 (``fftfreq``
        mode numbers ``mx``), ``ky = my / Ly`` along axis 1 (``rfftfreq``), in cycles per
        unit length (the integer mode numbers for unit sides). Multiply by ``2*pi`` for
        angular wavenumbers in rad per unit length: ``|q| = 2 pi sqrt(kx^2 + ky^2)``.
    """
    nx, ny = (shape, shape) if np.ndim(shape) == 0 else shape
    lx, ly = Cell.of((nx, ny), length).sides
    kx = np.fft.fftfreq(nx, d=1.0 / nx)[:, None] / lx
    ky = np.fft.rfftfreq(ny, d=1.0 / ny)[None, :] / ly
    return kx, ky


def rfft_weights(n: int) -> np.ndarray:
    """Multiplicity of each rfft2 column in the full spectrum, shape ``(1, n//2+1)``.

    Columns 1..ceil(n/2)-1 stand for themselves and their Hermitian mirror (weight 2);
    column 0 and, for even ``n``, the Nyquist column have weight 1. Sums over the full
    spectrum are ``(w * x).sum()`` over the half spectrum.
    """
    w = np.full((1, n // 2 + 1), 2.0)
    w[0, 0] = 1.0
    if n % 2 == 0:
        w[0, -1] = 1.0
    return w

"""The grid split in slabs over MPI ranks, and the distributed real 2-D FFT on it.

A case of ``nx x ny`` nodes is split along x (axis 0) into ``R`` slabs of consecutive rows, rank
``r`` holding rows ``[x0, x1)`` (:class:`Slabs`: ``nx // R`` rows each, the first ``nx % R`` ranks
one more). The spectrum of the real transform (``nx x (ny // 2 + 1)``) is split along the other
axis: rank ``r`` holds every row and the columns ``[c0, c1)`` of the half spectrum. A forward
transform is a real FFT along y on the slab, one all-to-all exchange (the transpose) and a complex
FFT along x; the inverse runs backwards. The inverse is unnormalised, as the batched solver's
(:class:`~roughcontact.solver.batch.halfspace.BatchOperator` keeps the ``1 / (nx ny)`` in its
multipliers).

Two implementations of that one layout (:data:`FFT_LIBRARIES`):

- ``"slab"`` (the default): pyFFTW's planned 1-D transforms, FFTW's or MKL's (:class:`FftwSlabFFT`: a machine's
  ranks write their blocks into each other's shared memory, ``Alltoallw`` takes the others; scipy.fft's and
  ``Alltoallv``, :class:`SlabFFT`, where pyFFTW is missing or not asked for), pip-installable with the ``mpi`` extra;
- ``"mpi4py-fft"`` (:class:`~.mpi4pyfft.MpiFFTPlan`): mpi4py-fft's ``PFFT`` on FFTW, which has no wheel on
  PyPI and builds only where FFTW's headers and libraries are installed (``libfftw3-dev``):
  measured against the first in ``benchmarks/README.md`` ("The solver over MPI ranks").
"""

from __future__ import annotations

import contextlib
import shutil

import numpy as np

from ...core import fftw_library
from .transpose import copy_transposed

#: Distributed FFT implementations :func:`make_fft` accepts.
FFT_LIBRARIES = ("slab", "mpi4py-fft")


def _complex_type(dtype):
    """The MPI datatype of a spectrum's values: complex64 or complex128."""
    from mpi4py import MPI

    return MPI.C_FLOAT_COMPLEX if np.dtype(dtype) == np.complex64 else MPI.C_DOUBLE_COMPLEX


def split(n: int, parts: int) -> list[tuple[int, int]]:
    """``[(start, stop), ...]``: ``n`` items in ``parts`` consecutive blocks, the first ``n % parts`` one larger."""
    base, extra = divmod(n, parts)
    stops = [0, *np.cumsum([base + (r < extra) for r in range(parts)]).tolist()]
    return list(zip(stops[:-1], stops[1:], strict=True))


#: Bytes of a memory page: each rank's part of a shared-memory window starts on one (FFTW plans an aligned buffer).
PAGE = 4096
#: The file system where MPI libraries keep the memory a machine's ranks share (MPICH and Open MPI, on Linux).
SHARED_MEMORY_DIR = "/dev/shm"


def fits_shared_memory(nbytes: int, path=SHARED_MEMORY_DIR) -> bool:
    """Whether ``path`` has ``nbytes`` free: True where it does not exist (the MPI library's own way then).

    A container's ``/dev/shm`` may be small (Docker's default: 64 MiB); there :class:`FftwSlabFFT` keeps each rank's
    spectra its own and sends every block through MPI.
    """
    try:
        return shutil.disk_usage(path).free >= nbytes
    except OSError:
        return True


class Slabs:
    """The slab decomposition of an ``(nx, ny)`` grid and its half spectrum over ``size`` ranks.

    Attributes: ``rows[r] = (x0, x1)`` (real-space rows of rank ``r``), ``cols[r] = (c0, c1)``
    (columns of the half spectrum, ``ny // 2 + 1`` in all), ``x0, x1, c0, c1`` this ``rank``'s.

    Raises
    ------
    ValueError
        When a rank would hold no row or no spectral column (more ranks than ``nx`` or than
        ``ny // 2 + 1``).
    """

    def __init__(self, shape, size: int, rank: int):
        self.shape = nx, ny = (int(shape[0]), int(shape[1]))
        self.size, self.rank = int(size), int(rank)
        nc = ny // 2 + 1
        if self.size > nx:
            raise ValueError(f"ranks: {self.size} MPI ranks for {nx} rows along x: each rank needs at least one "
                             f"row (run at most {nx} ranks)")
        if self.size > nc:
            raise ValueError(f"ranks: {self.size} MPI ranks for {nc} columns of the half spectrum (ny = {ny}): "
                             f"each rank needs at least one (run at most {nc} ranks)")
        self.rows, self.cols = split(nx, self.size), split(nc, self.size)
        self.x0, self.x1 = self.rows[self.rank]
        self.c0, self.c1 = self.cols[self.rank]
        self.local_shape = (self.x1 - self.x0, ny)
        self.spectrum_shape = (nx, self.c1 - self.c0)


class SlabFFT:
    """Real 2-D FFT of slabs: scipy.fft along each axis, mpi4py's ``Alltoallv`` for the transpose.

    ``forward`` takes the rank's real slab ``(B, x1 - x0, ny)`` and gives its part of the spectrum
    ``(B, nx, c1 - c0)``; ``backward`` the reverse, unnormalised. Either precision: float32 data
    give complex64 spectra. One rank skips the exchange (the serial transform).
    """

    name = "slab-scipy"  # the outputs' fft_backend: "mpi-" + name

    def __init__(self, comm, slabs: Slabs, threads: int = 1):
        import scipy.fft

        self.comm, self.slabs, self.sp = comm, slabs, scipy.fft
        self.workers = threads
        self.shape = slabs.shape

    def _exchange(self, send_blocks, recv_shapes, dtype):
        """Alltoallv of one contiguous block per rank; the received blocks, in rank order."""
        sendbuf = np.concatenate([b.reshape(-1) for b in send_blocks])
        counts = [int(np.prod(s)) for s in recv_shapes]
        recv = np.empty(sum(counts), dtype=dtype)
        scounts = [b.size for b in send_blocks]
        mt = _complex_type(dtype)
        self.comm.Alltoallv([sendbuf, (scounts, np.cumsum([0] + scounts[:-1])), mt],
                            [recv, (counts, np.cumsum([0] + counts[:-1])), mt])
        out, start = [], 0
        for shape, c in zip(recv_shapes, counts, strict=True):
            out.append(recv[start:start + c].reshape(shape))
            start += c
        return out

    def forward(self, x):
        """Spectrum ``(B, nx, c1 - c0)`` of the real slabs ``x`` ``(B, x1 - x0, ny)``."""
        s = self.slabs
        a = self.sp.rfft(x, axis=-1, workers=self.workers)
        if s.size > 1:
            B = a.shape[0]
            blocks = [a[:, :, c0:c1] for c0, c1 in s.cols]
            recv = self._exchange(blocks, [(B, x1 - x0, s.c1 - s.c0) for x0, x1 in s.rows], a.dtype)
            a = np.concatenate(recv, axis=1)
        return self.sp.fft(a, axis=-2, workers=self.workers, overwrite_x=True)

    def backward(self, spec):
        """The real slabs ``(B, x1 - x0, ny)`` of the spectrum part ``spec``, unnormalised."""
        s = self.slabs
        a = self.sp.ifft(spec, axis=-2, norm="forward", workers=self.workers, overwrite_x=True)
        if s.size > 1:
            B = a.shape[0]
            blocks = [a[:, x0:x1, :] for x0, x1 in s.rows]
            recv = self._exchange(blocks, [(B, s.x1 - s.x0, c1 - c0) for c0, c1 in s.cols], a.dtype)
            a = np.concatenate(recv, axis=2)
        return self.sp.irfft(a, n=self.shape[1], axis=-1, norm="forward", workers=self.workers)


class SlabPlans:
    """pyFFTW's plans and buffers of :class:`FftwSlabFFT` for one precision and batch ``B``.

    One rank: the 2-D pair over the whole grid, as the batched solver's (planned with the shipped
    wisdom). More: the real transforms along y of the rank's rows ``(B, rows, ny) <-> (B, rows,
    ny // 2 + 1)`` and the complex ones along x of its columns, held transposed ``(B, cols, nx)`` so
    that each column is contiguous (a transform striding along x is ~3x slower at 2048², and FFTW's
    estimating planner does not reorder it): each block is copied transposed.

    float32 (the iteration's products, ``in_place``): the real transforms write over their input, the rows'
    spectrum viewed as reals with padded rows (``real_in`` is ``real_out``); float64 (the refreshes) out of
    place. In place, a rank's float32 real transforms at 2048^2 on 2 ranks took 0.69x (forward) and 0.75x
    (inverse) the time out of place (2026-12-05, benchmarks/README.md, "The slab transforms in place").

    ``spectra``: the ``(row_spec, col_spec)`` buffers to use (this rank's part of a shared-memory window,
    :class:`FftwSlabFFT`), else its own; ``remote=False`` (every rank shares this one's memory) makes no
    exchange buffer. ``flags=None`` plans with the shipped wisdom alone
    (:data:`roughcontact.core.fft.PLANNER_FLAGS`); other flags (``("FFTW_MEASURE",)``) plan in FFTW's store as it
    is: :func:`write_wisdom` measures the shipped slab plans so.
    """

    def __init__(self, slabs: Slabs, B: int, real, threads: int, exchange=None, flags=None, spectra=None,
                 remote: bool = True):
        import pyfftw

        from ...core import fft as fft_module

        cplx = np.result_type(real, np.complex64)
        rows, ny = slabs.local_shape
        nx, cols = slabs.spectrum_shape
        nc = ny // 2 + 1
        # the spectra's two layouts: this rank's own buffers, or its part of its machine's shared window
        # (``spectra``: FftwSlabFFT, where the ranks that share its memory write their blocks straight in)
        self.row_spec = pyfftw.empty_aligned((B, rows, nc), dtype=cplx) if spectra is None else spectra[0]
        # float32 in place (the class docstring; one rank's 2-D pair where the wisdom holds it, as the single solve's);
        # float64 (the refreshes: a product's input is not needed once transformed) writes its output over its input
        self.in_place = real == np.float32 and (slabs.size > 1 or (B == 1 and fft_module.has_shipped_plans(
            slabs.shape)))
        if self.in_place:
            self.real_in = self.real_out = self.row_spec.view(real)[:, :, :ny]
        else:  # float32 out of place: the input stays the kernels' (they zero only what they wrote last)
            self.real_in = pyfftw.empty_aligned((B, rows, ny), dtype=real)
            self.real_out = pyfftw.empty_aligned((B, rows, ny), dtype=real) if real == np.float32 else self.real_in
        # planned with the shipped wisdom alone (core.fft), or measured with ``flags`` (write_wisdom: the shipped plans)
        kw = {"flags": fft_module.PLANNER_FLAGS if flags is None else tuple(flags), "threads": threads}
        with fft_module.shipped_wisdom_only() if flags is None else contextlib.nullcontext():
            if slabs.size == 1:
                self.col_spec = self.row_spec
                self.fwd = pyfftw.FFTW(self.real_in, self.row_spec, axes=(1, 2), direction="FFTW_FORWARD", **kw)
                self.bwd = pyfftw.FFTW(self.row_spec, self.real_out, axes=(1, 2), direction="FFTW_BACKWARD", **kw)
                return
            self.col_spec = pyfftw.empty_aligned((B, cols, nx), dtype=cplx) if spectra is None else spectra[1]
            # a forward sends the rank's rows of the half spectrum and receives its columns; a backward the
            # reverse. The blocks for ranks on other machines (``remote``) are packed (transposed) into one byte
            # buffer that serves both precisions (``exchange``: the other's, viewed); they are received in place
            self.exchange = self.send = None
            if remote:
                size = B * max(rows * nc, cols * nx) * np.dtype(cplx).itemsize
                if exchange is None or exchange.nbytes < size:
                    exchange = np.empty(size, dtype=np.uint8)
                self.exchange = exchange
                self.send = exchange[:size].view(cplx)
            self.types = {}  # FftwSlabFFT._receive_types' datatypes, by receiving buffer
            # planned on (B rows, n) views where MKL answers pyFFTW (it plans no 1-D transform batched over two axes)
            bufs = (self.real_in, self.row_spec, self.col_spec, self.real_out)
            ri, rs, cs, ro = map(fftw_library.one_batch_axis, bufs)
            self.rfft = pyfftw.FFTW(ri, rs, axes=(-1,), direction="FFTW_FORWARD", **kw)
            self.cfft = pyfftw.FFTW(cs, cs, axes=(-1,), direction="FFTW_FORWARD", **kw)
            self.icfft = pyfftw.FFTW(cs, cs, axes=(-1,), direction="FFTW_BACKWARD", **kw)
            self.irfft = pyfftw.FFTW(rs, ro, axes=(-1,), direction="FFTW_BACKWARD", **kw)


#: Grids and rank counts whose slab transforms :func:`write_wisdom` measures for the shipped wisdom: ``T N x N``
#: for ``N`` in ``WISDOM_SIZES`` and ``T`` in ``WISDOM_TILES`` (the square cells, and those tiled twice along x
#: that benchmarks/mpi/scaling.py's weak scaling solves), on each rank count of ``WISDOM_RANKS``. FFTW's
#: estimating planner alone cost 1.5-1.6x the measured plans' time for a float32 pair of a slab's transforms
#: at 1024^2 to 4096^2 on 2 ranks (2026-12-04, benchmarks/README.md, "The slab transforms' plans and transposes").
WISDOM_SIZES = (256, 512, 1024, 2048, 4096, 8192)
WISDOM_TILES = (1, 2)
WISDOM_RANKS = (2, 4, 8, 16, 32, 64)
#: FFTW_PATIENT's slab plans were no faster than FFTW_MEASURE's at 1024^2 and 2048^2 (2026-12-04) and took 17-30x
#: longer to make.
WISDOM_FLAGS = ("FFTW_MEASURE",)


def slab_problems(sizes=WISDOM_SIZES, ranks=WISDOM_RANKS, tiles=WISDOM_TILES) -> list:
    """The transforms :class:`FftwSlabFFT` plans (one case, both precisions) on ``T N x N`` over ``R`` ranks.

    For each ``N`` in ``sizes``, ``T`` in ``tiles`` and ``R`` in ``ranks`` (``R <= N // 2 + 1``), each
    slab shape its ranks hold (two at most: :func:`split` gives the first ranks one row or spectral
    column more) in each precision: a callable ``plan(flags)`` that makes that rank's plans with
    ``flags``, in FFTW's store as it is (:func:`roughcontact.core.fft.add_plans`).
    """
    problems, seen = [], set()
    for n, tile, size in ((n, t, r) for n in sizes for t in tiles for r in ranks):
        for rank in range(size if size <= n // 2 + 1 else 0):
            slabs = Slabs((tile * n, n), size, rank)
            if (slabs.local_shape, slabs.spectrum_shape) in seen:
                continue
            seen.add((slabs.local_shape, slabs.spectrum_shape))
            for real in (np.float64, np.float32):
                problems.append(lambda flags, s=slabs, r=real: SlabPlans(s, 1, r, 1, flags=flags))
    return problems


def write_wisdom(path=None, sizes=WISDOM_SIZES, ranks=WISDOM_RANKS, tiles=WISDOM_TILES, flags=WISDOM_FLAGS):
    """Measure the slab transforms of :func:`slab_problems` and add them to the shipped wisdom (``path``).

    Run on a quiet machine, once per FFTW build and processor model, after
    :func:`roughcontact.core.fft.write_wisdom` (``python -c "from roughcontact.solver.mpi.slabs import
    write_wisdom; write_wisdom()"``): the plans join the set this processor plans with
    (:func:`~roughcontact.core.fft.add_plans`, which says which of its plans stay), and the set records
    ``"slabs": {"sizes", "tiles", "ranks", "flags"}``. About 100 s of one core for the defaults (2026-12-04,
    Intel Xeon VM: 288 problems in 98 s).
    """
    from ...core import fft as fft_module

    record = {"slabs": {"sizes": list(sizes), "tiles": list(tiles), "ranks": list(ranks), "flags": list(flags)}}
    return fft_module.add_plans(slab_problems(sizes, ranks, tiles),
                                fft_module.WISDOM_FILE if path is None else path, record, flags)


class FftwSlabFFT(SlabFFT):
    """:class:`SlabFFT` with pyFFTW's planned transforms on buffers of their own (the default where pyFFTW
    imports): on one rank the single solve's 2-D transform; on more, the spectrum held transposed,
    ``(B, c1 - c0, nx)`` (:attr:`transposed`; :class:`~.kernels.SlabOperator` makes its multipliers so).

    The transpose between the two layouts moves each block once where it can. The ranks on one machine
    (``node``: by default ``comm.Split_type(COMM_TYPE_SHARED)``) hold their spectra in one MPI shared-memory
    window, and each copies its blocks, transposed, straight into the others' (between two barriers of the
    machine's ranks). A block for a rank on another machine is packed transposed and sent (``Alltoallw``, received
    in place). A whole solve on 2 ranks took 0.95-0.97x the CPU of the exchange through MPI (which copies each
    block twice more) at 2048^2, 0.88-0.91x at 4096^2 (benchmarks/README.md, "The transposes through shared memory").

    :attr:`input32` is the float32 forward transform's input buffer (B = 1), where the kernels write, and the
    float32 inverse's output (:class:`SlabPlans`, in place: either transform writes over it and calls
    :attr:`on_overwrite`); :meth:`forward` returns the spectrum's buffer and :meth:`backward` the real output's,
    valid until the next transform of that precision (a caller keeps a copy of what it needs). :meth:`close` frees the
    windows (collective). :attr:`peer_parts` lists ``(address, bytes)`` of the other ranks' parts of them, which this
    rank maps where it writes (benchmarks/mpi/scaling.py counts them apart from a rank's own memory).

    ``node`` (an ``mpi4py`` communicator, optional): the ranks of ``comm`` whose memory this rank shares, this one
    included (a communicator of one: every block through MPI); default, those on its machine.
    """

    def __init__(self, comm, slabs: Slabs, threads: int = 1, node=None):
        super().__init__(comm, slabs, threads)
        self.name = "slab" + fftw_library.fft_label("pyfftw").removeprefix("pyfftw")  # "slab", "slab-mkl"
        self._plans = {}
        self._windows = []
        self.peer_parts = []  # (address, bytes) of the other ranks' parts of the windows (memory measurements)
        self.transposed = slabs.size > 1
        # called after a float32 transform has written over input32 (SlabPlans.in_place; set by SlabOperator:
        # the kernels' next sparse write there zeroes all of it)
        self.on_overwrite = None
        self.node, self.local, self._split = None, (slabs.rank,), None
        if slabs.size > 1:
            if node is None:
                from mpi4py import MPI

                node = self._split = comm.Split_type(MPI.COMM_TYPE_SHARED, key=comm.rank)
            # the ranks of comm this one shares memory with, by their rank in ``node``, if the machine has room for
            # their spectra in both precisions (decided once for all of them)
            local = tuple(node.allgather(comm.rank))
            room = node.size > 1 and node.bcast(fits_shared_memory(sum(
                self._part(r, 1, c)[2] for r in local for c in (np.complex64, np.complex128))))
            if room:
                self.node, self.local = node, local
        self.input32 = self.plans(1, np.float32).real_in
        self.plans(1, np.float64)  # its window made here too, where a failure is one line (MpiSolver: collective)

    def plans(self, B: int, real) -> SlabPlans:
        """The plans of ``B`` cases in precision ``real`` (float32 or float64), made at first use (collective over
        the machine's ranks, which make theirs at the same transform)."""
        key = (int(B), np.dtype(real))
        if key not in self._plans:
            exchanges = [p.exchange for p in self._plans.values() if getattr(p, "exchange", None) is not None]
            spectra = self._shared_spectra(B, real) if self.node is not None else None
            p = SlabPlans(self.slabs, B, real, self.workers, exchanges[0] if exchanges else None,
                          spectra=None if spectra is None else spectra[self.slabs.rank],
                          remote=len(self.local) < self.slabs.size)
            self._plans[key] = p
            # the blocks' destinations: this rank's own buffers, and those of the ranks sharing its memory
            p.spectra = spectra or {self.slabs.rank: (p.row_spec, p.col_spec)}
            if exchanges and p.exchange is not exchanges[0]:  # larger now: every plan uses it
                for q in self._plans.values():
                    if q.exchange is not None:
                        q.exchange = p.exchange
                        q.send = q.exchange[:q.send.nbytes].view(q.send.dtype)
        return self._plans[key]

    def _shared_spectra(self, B: int, real) -> dict:
        """``{rank: (row_spec, col_spec)}`` of every rank on this machine, in one shared-memory window (made here,
        collectively over :attr:`node`; each rank's part page-aligned, so FFTW plans them as its own buffers)."""
        from mpi4py import MPI

        cplx = np.dtype(np.result_type(real, np.complex64))
        nx, ny = self.slabs.shape
        info = MPI.Info.Create()
        info.Set("alloc_shared_noncontig", "true")  # each rank's part on its own pages, near its core
        try:
            win = MPI.Win.Allocate_shared(self._part(self.slabs.rank, B, cplx)[2], 1, info, comm=self.node)
        except MPI.Exception as exc:
            need = sum(self._part(r, B, cplx)[2] for r in self.local) / 2**20
            raise OSError(f"ranks: the shared memory for this machine's {len(self.local)} ranks' spectra ({need:.1f} "
                          f"MiB in {SHARED_MEMORY_DIR}) could not be had ({exc.Get_error_string()}); free room there "
                          f"(df {SHARED_MEMORY_DIR}), or give a container more (docker run --shm-size)") from exc
        finally:
            info.Free()
        self._windows.append(win)
        out = {}
        for i, rank in enumerate(self.local):
            s, at, _ = self._part(rank, B, cplx)
            buf = win.Shared_query(i)[0]
            if rank != self.slabs.rank:
                self.peer_parts.append((buf.address, buf.nbytes))
            out[rank] = (np.ndarray((B, s.local_shape[0], ny // 2 + 1), cplx, buf),
                         np.ndarray((B, s.spectrum_shape[1], nx), cplx, buf, offset=at))
        return out

    def _part(self, rank: int, B: int, cplx) -> tuple:
        """``(slabs, offset, size)`` of ``rank``'s part of a window [B]: its ``row_spec``, then from the next page
        (``offset``) its ``col_spec``, up to a whole page."""
        s = Slabs(self.slabs.shape, self.slabs.size, rank)
        nx, ny = self.slabs.shape
        item = np.dtype(cplx).itemsize
        at = -(-B * s.local_shape[0] * (ny // 2 + 1) * item // PAGE) * PAGE
        return s, at, at + -(-B * s.spectrum_shape[1] * nx * item // PAGE) * PAGE

    def close(self) -> None:
        """Free the shared-memory windows (collective over the machine's ranks) and the exchanges' datatypes; the
        transforms are spent after."""
        for t in (t for p in self._plans.values() for types in getattr(p, "types", {}).values() for t in types):
            t.Free()
        for win in self._windows:
            win.Free()
        if self._split is not None:
            self._split.Free()
        self._windows, self._plans, self._split, self.peer_parts = [], {}, None, []
        self.input32 = None

    def _receive_types(self, p: SlabPlans, dst, dst_parts) -> list:
        """MPI datatypes that put rank ``r``'s block straight into ``dst[:, :, d0:d1]`` (made once a buffer).

        A vector of ``B m`` rows of ``d1 - d0`` values, ``dst.shape[2]`` apart: the received block lands in
        place, with no unpacking copy and no receive buffer. Measured at 2048² on 2 ranks (2026-12-02,
        benchmarks/README.md): a whole solve's CPU per rank 0.96-0.99 of the unpacking version's. Sending with
        datatypes too (the transpose done by MPI) cost 3x in a microbenchmark: MPICH packs such a type value by
        value.
        """
        key = (id(dst), tuple(dst_parts))
        types = p.types.get(key)
        if types is None:
            B, m, k = dst.shape
            types = p.types[key] = [_complex_type(dst.dtype).Create_vector(B * m, d1 - d0, k).Commit()
                                    for d0, d1 in dst_parts]
        return types

    def _transpose(self, p: SlabPlans, src, layout: int, src_parts, dst_parts) -> None:
        """The all-to-all transpose between the rows' and the columns' layouts, either way.

        ``src`` is ``(B, m, k)`` and so is the destination, ``layout`` 0 (``row_spec``) or 1 (``col_spec``), each
        with this rank's share of the other axis first: rank ``r`` gets ``src[:, :, a0:a1]`` transposed
        (``(a0, a1) = src_parts[r]``), and what rank ``r`` sends lands in ``dst[:, :, d0:d1]`` (``(d0, d1) =
        dst_parts[r]``). A rank sharing this one's memory (this one too) gets its block copied into its buffer
        directly; the others' go through ``Alltoallw``.
        """
        me = self.slabs.rank
        d0, d1 = dst_parts[me]
        if self.node is not None:
            self.node.Barrier()  # each rank of the machine is in this transform: what its buffer held is spent
        for rank, spectra in p.spectra.items():
            a0, a1 = src_parts[rank]
            copy_transposed(spectra[layout][:, :, d0:d1], src[:, :, a0:a1])
        if len(self.local) < self.slabs.size:
            self._send(p, src, (p.row_spec, p.col_spec)[layout], src_parts, dst_parts)
        if self.node is not None:
            self.node.Barrier()  # every block from this machine's ranks is in place

    def _send(self, p: SlabPlans, src, dst, src_parts, dst_parts) -> None:
        """The blocks of :meth:`_transpose` to and from ranks on other machines: packed transposed, one
        ``Alltoallw``, received in place (:meth:`_receive_types`)."""
        B, item = src.shape[0], p.send.itemsize
        counts, send_displs, at = [], [], 0
        for r, (a0, a1) in enumerate(src_parts):
            n = 0 if r in self.local else B * (a1 - a0) * src.shape[1]
            if n:
                copy_transposed(p.send[at:at + n].reshape(B, a1 - a0, src.shape[1]), src[:, :, a0:a1])
            counts.append(n)
            send_displs.append(at * item)  # Alltoallw takes byte displacements
            at += n
        # rank r's block received in place: one value of its vector type, at byte offset d0 of dst's rows
        recv_counts = [0 if r in self.local or d1 == d0 else 1 for r, (d0, d1) in enumerate(dst_parts)]
        recv_displs = [d0 * item for d0, _ in dst_parts]
        self.comm.Alltoallw([p.send, counts, send_displs, [_complex_type(p.send.dtype)] * len(counts)],
                            [dst, recv_counts, recv_displs, self._receive_types(p, dst, dst_parts)])

    def forward(self, x):
        p = self.plans(x.shape[0], x.dtype)
        if x is not p.real_in:
            p.real_in[...] = x
        s = self.slabs
        if s.size == 1:
            p.fwd.execute()
            self._overwritten(p)
            return p.row_spec
        p.rfft.execute()
        self._overwritten(p)
        # to rank r: this rank's rows of r's spectral columns, transposed
        self._transpose(p, p.row_spec, 1, s.cols, s.rows)
        p.cfft.execute()
        return p.col_spec

    def backward(self, spec):
        real = np.float32 if spec.dtype == np.complex64 else np.float64
        p = self.plans(spec.shape[0], real)
        if spec is not p.col_spec:
            p.col_spec[...] = spec
        s = self.slabs
        if s.size == 1:
            p.bwd.execute()  # destroys the spectrum
            self._overwritten(p)
            return p.real_out
        p.icfft.execute()
        # to rank r: its rows of this rank's spectral columns, transposed
        self._transpose(p, p.col_spec, 0, s.rows, s.cols)
        p.irfft.execute()  # destroys row_spec
        self._overwritten(p)
        return p.real_out

    def _overwritten(self, p: SlabPlans) -> None:
        if p.in_place and self.on_overwrite is not None:
            self.on_overwrite()


def make_fft(library: str, comm, slabs: Slabs, threads: int = 1):
    """The distributed FFT named ``library`` (:data:`FFT_LIBRARIES`) on ``slabs``."""
    if library not in FFT_LIBRARIES:
        raise ValueError(f"fft_library must be one of {FFT_LIBRARIES}, got {library!r}")
    if library == "mpi4py-fft":
        from .mpi4pyfft import MpiFFTPlan

        return MpiFFTPlan(comm, slabs, threads)
    from ...core import fft as fft_module

    # pyFFTW's plans where it is asked for and FFTW or MKL answers it (core.fftw_library), else SciPy's
    fftw = fft_module.default_backend() == "pyfftw" and fftw_library.pyfftw_library() in ("fftw", "mkl")
    return FftwSlabFFT(comm, slabs, threads) if fftw else SlabFFT(comm, slabs, threads)

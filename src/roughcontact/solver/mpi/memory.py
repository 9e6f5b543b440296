"""The peak memory of one rank of a case over MPI ranks, from measurements: :func:`rank_memory_mib`.

A rank holds its slab's rows of every field, the transposes' buffers and the warm start's last two solutions (all in
proportion to the nodes of its slab), an interpreter with numpy, numba's compiled kernels, pyFFTW and mpi4py (a
constant), and a little for every other rank of the job on its machine (MPICH's shared-memory state, presumably).
The three constants below are fitted to peak resident memory (``ru_maxrss``) measured per rank with 1 to 64 ranks on
grids of 256² to 8192² (benchmarks/README.md, "Memory a rank", 2026-12-03; ``benchmarks/mpi/memory.py``): the
fullest rank of every run of 2 ranks or more on the grids of 2048² and more within -5.0 % and +1.6 % of the model;
the 256² grid's (6-9 % below) and one rank's (2-D plans, no exchange buffers; 8-11 % below) under it.

Since 2026-12-04 the ranks of a machine hold their spectra in one shared-memory window (:class:`.slabs.FftwSlabFFT`).
What a rank holds of its own (its peak RSS less the other ranks' window pages it maps, which the machine holds once)
fell 0.4-4.3 % on 2 ranks or more: the same runs lie 0.4-11 % under the model, which is kept as a bound
(benchmarks/README.md, "With the shared windows"). A rank's RSS also counts those pages: where a site limits the sum
of the ranks' RSS rather than what a memory cgroup charges, a rank may need more than the ``contact`` rule asks (up
to 1.007x its share measured, at 4096² on 8 ranks; about 1.18x for 32768² on 128 ranks of one node, by the layout).
Since 2026-12-05 the float32 slab transforms run in place (8 B a node less): every run lies 2.7-15.6 % under the
model, every peak RSS under the rule's share (at most 0.986x; benchmarks/README.md, "With the slab transforms in
place").
"""

from __future__ import annotations

from .slabs import split

#: A rank's memory that does not grow with its slab [MiB]: the interpreter and libraries, and per-slab buffers.
RANK_MIB = 270.0
#: A rank's memory for each rank of the job on its machine [MiB] (measured 0.605 MiB a rank more from 8 to 64 ranks
#: on a 256² grid, all on one machine: MPICH's shared-memory state, presumably; ranks on other machines are not
#: measured).
PER_RANK_OF_JOB_MIB = 0.6
#: A rank's memory for each node of its slab [B]: the fields, the transposes' buffers, the warm start's solutions
#: (fitted 166.1 B on the grids of 2048² to 8192²; 152 B before the fused kernels of 2026-12-02).
BYTES_PER_NODE = 170.0


def largest_slab_nodes(shape, ranks: int) -> int:
    """Nodes of the largest slab when an ``(nx, ny)`` grid is split into ``ranks`` slabs of rows as the solver splits
    it (:func:`~roughcontact.solver.mpi.slabs.split`: the first slab is one of the largest)."""
    start, stop = split(int(shape[0]), int(ranks))[0]
    return (stop - start) * int(shape[1])


def rank_memory_mib(shape, ranks: int, *, ranks_per_machine: int | None = None, rank_mib: float = RANK_MIB,
                    per_rank_of_job_mib: float = PER_RANK_OF_JOB_MIB, bytes_per_node: float = BYTES_PER_NODE) -> float:
    """Peak resident memory of the fullest rank of a case of ``shape`` nodes over ``ranks`` ranks [MiB], as measured
    (no margin).

    Parameters
    ----------
    shape : tuple of int
        The grid ``(nx, ny)``, split along ``nx``.
    ranks : int
        MPI ranks of the job.
    ranks_per_machine : int, optional
        Ranks of the job on the rank's machine (default ``ranks``: all on one, as measured).
    rank_mib, per_rank_of_job_mib, bytes_per_node : float, optional
        The model's constants (default: the measured :data:`RANK_MIB`, :data:`PER_RANK_OF_JOB_MIB`,
        :data:`BYTES_PER_NODE`); another machine's or MPI library's, re-measured, go here.

    Returns
    -------
    float
        ``rank_mib + per_rank_of_job_mib * ranks_per_machine + bytes_per_node * nodes / 2**20``, ``nodes`` those of
        the largest slab (:func:`largest_slab_nodes`).

    Examples
    --------
    The Contact-Mechanics-Challenge size on the 128 cores of one node, each rank 256 rows of 32768:

    >>> round(rank_memory_mib((32768, 32768), 128))
    1707
    """
    together = int(ranks) if ranks_per_machine is None else min(int(ranks), int(ranks_per_machine))
    return rank_mib + per_rank_of_job_mib * together + bytes_per_node * largest_slab_nodes(shape, ranks) / 2**20

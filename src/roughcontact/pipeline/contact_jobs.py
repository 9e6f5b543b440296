"""What the contact rules ask of a scene: each case's input, the batches of ``contact.solver.batch``, resources.

With ``contact.solver.batch: B`` (> 1) the seeds of each ``(k_l, k_s, H)`` are solved ``B`` at a time
(:func:`roughcontact.pipeline.cases.contact_batches`) by the ``contact_batch`` rule, whose file
(:func:`contact_batch_path`) holds one group per case, and each case's ``contact`` job copies its group
out (:meth:`ContactJobs.contact_input` names the batch file as its input). With ``contact.solver.ranks: R``
(> 1) each case is solved over ``R`` MPI processes by the ``contact_mpi`` rule (an MPI job: Snakemake's
``mpi`` and ``tasks`` resources), whose file ``results/{scene}/contact_mpi/<case>.nc`` the case's ``contact``
job copies, as it copies a batch's group: the MPI job stays out of the SLURM profile's group of contact jobs.
:class:`ContactJobs` holds the functions the rules call with a job's wildcards;
:class:`roughcontact.pipeline.targets.Targets` is one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from snakemake.exceptions import WorkflowError

from .cases import CASE_STEM, CONTACT_BATCH_STEM, ContactBatch, batch_index, batch_seeds, batch_size

__all__ = ["COPY_MEM_MB", "COPY_RUNTIME_MIN", "ContactJobs", "contact_batch_mem_mb", "contact_batch_path",
           "contact_batch_runtime_min", "contact_mem_mb", "contact_mpi_mem_mb", "contact_mpi_runtime_min",
           "contact_runtime_min", "map_side", "ranks_of"]


def contact_batch_path(folder: str, ext: str = "nc") -> str:
    """Pattern of one contact batch's file (``contact.solver.batch`` > 1): ``results/{scene}/<folder>/``
    ``kl{k_l}_ks{k_s}_H{H}_b{batch}.<ext>`` (:class:`~.cases.ContactBatch`)."""
    return f"results/{{scene}}/{folder}/{CONTACT_BATCH_STEM}.{ext}"


def map_side(surface: Mapping) -> float:
    """The side N of the square map with as many nodes as a generated study's ``surface`` block makes: ``N``, or
    ``sqrt(N)`` for profiles of N points (``dimension: 1``), so that the resource formulas (functions of a map's
    side) hold for both."""
    n = surface["N"]
    return math.sqrt(n) if surface.get("dimension") == 1 else n


def contact_mem_mb(n: int) -> int:
    """Peak memory of one contact job [MB]: interpreter + libraries + ~40 N^2 doubles of solver work."""
    return int(300 + 40 * 8 * n * n / 2**20)


def contact_runtime_min(n: int, n_steps: int) -> int:
    """Wall-time request of one contact job [min]: 30 steps at N=1024 take 15-130 s (paper grid); x9 margin."""
    return max(5, int(10 * n_steps / 30 * (n / 1024) ** 2 * 2))


def contact_batch_mem_mb(n: int, size: int) -> int:
    """Peak memory of one contact batch job of ``size`` cases [MB]: :func:`contact_mem_mb`'s solver work per case."""
    return int(300 + size * 40 * 8 * n * n / 2**20)


def contact_batch_runtime_min(n: int, n_steps: int, size: int) -> int:
    """Wall-time request of one contact batch job [min]: ``size`` cases at :func:`contact_runtime_min`'s pace
    (on the host a batch is no faster than its cases one by one)."""
    return max(5, size * contact_runtime_min(n, n_steps))


def ranks_of(block: Mapping) -> int:
    """The MPI processes one case of a validated contact block is split over: ``solver.ranks`` (absent: 1)."""
    return int(block["solver"].get("ranks", 1))


def contact_mpi_mem_mb(n: int, ranks: int) -> int:
    """Peak memory of one contact case over ``ranks`` MPI processes [MB], all ranks together: an interpreter per
    rank and 40 doubles a node of solver work, split (a margin: measured at N = 8192 on 2 ranks, 206 B a node and
    0.25 GiB a rank since the fused kernels of 2026-12-02, 152 B before: benchmarks/README.md)."""
    return int(300 * ranks + 40 * 8 * n * n / 2**20)


def contact_mpi_runtime_min(n: int, n_steps: int, ranks: int) -> int:
    """Wall-time request of one contact case over ``ranks`` processes [min]: :func:`contact_runtime_min` x 4, shared
    by the ranks (a margin: the distributed iteration's CPU per iteration was 3.6-4.1x the single solve's before the
    fused kernels of 2026-12-02, 1.14x on one rank and 0.70x a rank on two since; the transposes of many ranks and
    a cluster's shared memory bandwidth are not measured here)."""
    return max(5, math.ceil(4 * contact_runtime_min(n, n_steps) / ranks))


#: Peak memory [MB] and wall time [min] of a batched case's own job: it copies its case out of its batch's file.
COPY_MEM_MB, COPY_RUNTIME_MIN = 300, 5


def _case_of(w) -> dict:
    """A generated case's wildcards (``k_l``, ``k_s``, ``H``, ``seed``) as :data:`CASE_STEM`'s fields."""
    return {"k_l": w.k_l, "k_s": w.k_s, "H": w.H, "seed": w.seed}


class ContactJobs:
    """The contact rules' functions of a job's wildcards (a mixin of :class:`~.targets.Targets`).

    The class it is mixed into supplies ``scenes`` (the validated scenes), ``check_grid_values(w, study)``
    and ``check_case(w, study)`` (a requested file's wildcards checked against its scene's grid, with the
    allowed values named).
    """

    def contact_batch_of(self, w) -> ContactBatch:
        """The contact batch named by a job's wildcards (``k_l``, ``k_s``, ``H``, ``batch``), checked against its
        scene: a grid value outside the grid, a scene that batches nothing or a batch past its seeds is named."""
        block = self.check_grid_values(w, "contact")
        size = batch_size(block)
        if size == 1:
            raise WorkflowError(f"scene {w.scene!r} solves each contact case alone (contact.solver.batch is 1), so it "
                                f"has no contact batch files; its cases are results/{w.scene}/contact/{CASE_STEM}.nc")
        n_batches = -(-block["seeds"] // size)
        if w.batch != str(int(w.batch)) or int(w.batch) >= n_batches:
            raise WorkflowError(f"scene {w.scene!r}, contact: wildcard batch={w.batch} is not one of the scene's "
                                f"batches 0..{n_batches - 1} ({block['seeds']} seeds in batches of {size}; written "
                                "without leading zeros)")
        index = int(w.batch)
        return ContactBatch(w.k_l, w.k_s, w.H, index, batch_seeds(index, size, block["seeds"]))

    def contact_batch_input(self, w) -> list[str]:
        """The surfaces of a contact batch's cases, in seed order (the order of its solve)."""
        return [f"results/{w.scene}/surfaces/{case.stem}.nc" for case in self.contact_batch_of(w).cases]

    def contact_batch_seeds(self, w) -> list[int]:
        """A params function: the seeds of a contact batch, in the order of its input surfaces."""
        return list(self.contact_batch_of(w).seeds)

    def contact_batch_params(self, provider):
        """A params function: ``provider``'s values for the contact block of a batch's scene, once the batch is
        checked."""

        def values(w):
            self.contact_batch_of(w)
            return provider(self.scenes[w.scene]["contact"])

        return values

    def contact_input(self, w) -> dict:
        """The input of one contact case's job (the case checked against its scene's grid): its surface
        (``surface``), with ``contact.solver.batch`` > 1 its batch's file (``batch``), with ``contact.solver.ranks``
        > 1 its MPI job's file (``mpi``): the job copies its case out of either."""
        block = self.check_case(w, "contact")
        size = batch_size(block)
        if ranks_of(block) > 1:
            return {"mpi": f"results/{w.scene}/contact_mpi/{CASE_STEM.format(**_case_of(w))}.nc"}
        if size == 1:
            return {"surface": f"results/{w.scene}/surfaces/{CASE_STEM.format(**_case_of(w))}.nc"}
        stem = CONTACT_BATCH_STEM.format(k_l=w.k_l, k_s=w.k_s, H=w.H, batch=batch_index(w.seed, size))
        return {"batch": f"results/{w.scene}/contact_batch/{stem}.nc"}

    def contact_job_mem_mb(self, w) -> int:
        """Peak memory of one contact case's job [MB]: a solve's (:func:`contact_mem_mb`), or a batched or MPI
        case's copy."""
        block = self.scenes[w.scene]["contact"]
        if batch_size(block) > 1 or ranks_of(block) > 1:
            return COPY_MEM_MB
        return contact_mem_mb(map_side(block["surface"]))

    def contact_job_runtime_min(self, w) -> int:
        """Wall-time request of one contact case's job [min]: a solve's (:func:`contact_runtime_min`), or a copy's."""
        block = self.scenes[w.scene]["contact"]
        if batch_size(block) > 1 or ranks_of(block) > 1:
            return COPY_RUNTIME_MIN
        return contact_runtime_min(map_side(block["surface"]), block["load"]["n_steps"])

    def batch_job_mem_mb(self, w) -> int:
        """Peak memory of one contact batch job [MB] (:func:`contact_batch_mem_mb` of the scene's N and batch)."""
        block = self.scenes[w.scene]["contact"]
        return contact_batch_mem_mb(block["surface"]["N"], batch_size(block))

    def batch_job_runtime_min(self, w) -> int:
        """Wall-time request of one contact batch job [min] (:func:`contact_batch_runtime_min`)."""
        block = self.scenes[w.scene]["contact"]
        return contact_batch_runtime_min(block["surface"]["N"], block["load"]["n_steps"], batch_size(block))

    def contact_mpi_block(self, w) -> Mapping:
        """The contact block of a case over MPI ranks, the case checked against its scene: a scene that solves its
        cases in one process (``contact.solver.ranks`` 1) has no ``contact_mpi`` files, and says so."""
        block = self.check_case(w, "contact")
        if ranks_of(block) == 1:
            raise WorkflowError(f"scene {w.scene!r} solves each contact case in one process (contact.solver.ranks is "
                                f"1), so it has no contact_mpi files; its cases are "
                                f"results/{w.scene}/contact/{CASE_STEM}.nc")
        return block

    def contact_mpi_input(self, w) -> str:
        """The surface of a case over MPI ranks (every rank reads its rows of it)."""
        self.contact_mpi_block(w)
        return f"results/{w.scene}/surfaces/{CASE_STEM.format(**_case_of(w))}.nc"

    def contact_mpi_params(self, provider):
        """A params function: ``provider``'s values for the contact block of a case over MPI ranks."""
        return lambda w: provider(self.contact_mpi_block(w))

    def mpi_job_tasks(self, w) -> int:
        """MPI processes of one case's ``contact_mpi`` job: ``contact.solver.ranks`` (SLURM's ``--ntasks``)."""
        return ranks_of(self.scenes[w.scene]["contact"])

    def mpi_job_mem_mb(self, w) -> int:
        """Peak memory of one ``contact_mpi`` job [MB], all ranks (:func:`contact_mpi_mem_mb`)."""
        block = self.scenes[w.scene]["contact"]
        return contact_mpi_mem_mb(block["surface"]["N"], ranks_of(block))

    def mpi_job_runtime_min(self, w) -> int:
        """Wall-time request of one ``contact_mpi`` job [min] (:func:`contact_mpi_runtime_min`)."""
        block = self.scenes[w.scene]["contact"]
        return contact_mpi_runtime_min(block["surface"]["N"], block["load"]["n_steps"], ranks_of(block))

"""What the one ``contact`` rule asks of a scene: each job's group of cases, its input, params and resources.

A contact job solves a *group* and writes its file ``results/{scene}/contact/{group}.nc`` (:func:`contact_path`)
once:

* one case (``kl{k_l}_ks{k_s}_H{H}_s{seed}``: :data:`~.cases.CASE_STEM`), solved in one process, or over
  ``contact.solver.ranks: R`` (> 1) MPI processes: an MPI job (Snakemake's ``mpi`` and ``tasks`` resources), the
  ranks started by :func:`roughcontact.case.run_case`;
* with ``contact.solver.batch: B`` (> 1), the seeds ``b B .. (b + 1) B - 1`` of one ``(k_l, k_s, H)``
  (``kl{k_l}_ks{k_s}_H{H}_b{b}``: :data:`~.cases.CONTACT_BATCH_STEM`, :func:`~.cases.contact_batches`), solved
  together; the file holds one NetCDF group per case (:func:`roughcontact.pipeline.io.write_groups`), which the
  aggregate reads (:meth:`ContactJobs.contact_members_of`);
* a named case of a patch source (a measured or array file): ``{topography}``.

:class:`ContactJobs` holds the functions the rule calls with a job's wildcards;
:class:`roughcontact.pipeline.targets.Targets` is one.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from types import SimpleNamespace

from snakemake.exceptions import WorkflowError

from ..solver.mpi.memory import rank_memory_mib
from .cases import (
    CASE_STEM,
    CONTACT_BATCH_STEM,
    Case,
    ContactBatch,
    batch_index,
    batch_seeds,
    batch_size,
    contact_batches,
)
from .sources import SOURCES, PatchSource

__all__ = ["BUNDLE", "MPI_MEMORY_MARGIN", "NAMED_RUNTIME_MIN", "ContactGroup", "ContactJobs", "check_seed",
           "contact_batch_mem_mb", "contact_batch_runtime_min", "contact_mem_mb", "contact_mpi_mem_mb",
           "contact_mpi_runtime_min", "contact_path", "contact_runtime_min", "map_side", "mpi_mem_mb_per_cpu",
           "ranks_of"]


def contact_path(folder: str, ext: str = "nc") -> str:
    """Pattern of one contact job's file: ``results/{scene}/<folder>/{group}.<ext>``, the group's stem (one case, a
    batch of seeds, or a named case: the module's docstring)."""
    return f"results/{{scene}}/{folder}/{{group}}.{ext}"


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


#: The share the ``contact`` rule asks above a rank's measured peak memory (:func:`contact_mpi_mem_mb`).
MPI_MEMORY_MARGIN = 1.1


def contact_mpi_mem_mb(n: int, ranks: int) -> int:
    """Peak memory of one contact case over ``ranks`` MPI processes [MiB, as Snakemake's ``mem_mb`` and SLURM's
    ``--mem-per-cpu`` read it], all ranks together: ``ranks`` times the fullest rank's peak by the measured model
    (:func:`roughcontact.solver.mpi.rank_memory_mib`: an interpreter, MPI's buffers and 170 B a node of its slab)
    and :data:`MPI_MEMORY_MARGIN`, rounded up to whole MiB a rank. The fullest rank of every
    run measured with 1-64 ranks on 256²-8192² grids (2026-12-03) peaked at 0.807-0.923 of its share of this."""
    return ranks * math.ceil(MPI_MEMORY_MARGIN * rank_memory_mib((n, n), ranks))


def mpi_mem_mb_per_cpu(mem_mb: int, ranks: int, threads: int = 1) -> int:
    """A job's ``mem_mb`` (all ranks together) over its ``ranks x threads`` CPUs [MB], rounded up: the
    ``mem_mb_per_cpu`` (SLURM's ``--mem-per-cpu``) of a case over MPI ranks, whose memory then follows its ranks
    to whatever nodes SLURM puts them on."""
    return -(-int(mem_mb) // (int(ranks) * max(1, int(threads))))


def contact_mpi_runtime_min(n: int, n_steps: int, ranks: int) -> int:
    """Wall-time request of one contact case over ``ranks`` processes [min]: :func:`contact_runtime_min` x 4, shared
    by the ranks (a margin: the distributed iteration's CPU per iteration was 3.6-4.1x the single solve's before the
    fused kernels of 2026-12-02, then 1.14x on one rank and 0.70x a rank on two, 0.97-1.00x and 0.55-0.59x at
    2048² since the compressed vectors; the transposes of many ranks and
    a cluster's shared memory bandwidth are not measured here)."""
    return max(5, math.ceil(4 * contact_runtime_min(n, n_steps) / ranks))


def check_seed(scene: str, where: str, seed: str, n_seeds: int) -> None:
    """Stop unless ``seed`` is one of the scene's seeds 0..n_seeds-1, written without leading zeros."""
    if seed != str(int(seed)) or int(seed) >= n_seeds:
        raise WorkflowError(
            f"scene {scene!r}, {where}: wildcard seed={seed} is not one of the scene's seeds 0..{n_seeds - 1} "
            "(written without leading zeros)"
        )


#: The SLURM profile's bundle of small jobs that contact jobs join (``group-components`` there); a job over MPI
#: ranks joins none (its allocation is its ranks').
BUNDLE = "solve"

#: Wall-time request of a named case's contact job [min].
NAMED_RUNTIME_MIN = 60

#: A group's stem, parsed: one generated case, or one batch of seeds of a ``(k_l, k_s, H)``.
_CASE = re.compile(r"kl(?P<k_l>[^_/]+)_ks(?P<k_s>[^_/]+)_H(?P<H>[^_/]+)_s(?P<seed>\d+)")
_BATCH = re.compile(r"kl(?P<k_l>[^_/]+)_ks(?P<k_s>[^_/]+)_H(?P<H>[^_/]+)_b(?P<batch>\d+)")


@dataclass(frozen=True)
class ContactGroup:
    """What one contact job solves: its kind, its file's stem, its cases and its scene's contact block.

    Attributes
    ----------
    kind : {"case", "ranks", "batch", "named"}
        One generated case in one process, one over MPI ranks, a batch of seeds, or a patch source's named case.
    stem : str
        The file's stem (the ``group`` wildcard).
    members : tuple
        The group's cases in the order of the solve: :class:`~.cases.Case` (generated), or the named case's name.
    block : Mapping
        The scene's validated ``contact`` block.
    ranks : int
        MPI processes of the job (1 but for ``"ranks"``).
    """

    kind: str
    stem: str
    members: tuple
    block: Mapping
    ranks: int = 1

    @property
    def stems(self) -> list[str]:
        """The file stems of its cases (their surfaces' files under ``results/{scene}/surfaces/``)."""
        return [m.stem if isinstance(m, Case) else m for m in self.members]


class ContactJobs:
    """The ``contact`` rule's functions of a job's wildcards (a mixin of :class:`~.targets.Targets`).

    The class it is mixed into supplies ``scenes`` (the validated scenes), ``scene_source``, ``study_block``,
    ``generated_block``, ``check_grid_values(w, study)``, ``check_topography(w, study)`` and ``measured_mem_mb(w)``
    (a requested file's wildcards checked against its scene, with the allowed values named).
    """

    def contact_group(self, w) -> ContactGroup:
        """The group a contact job's ``group`` wildcard names, checked against its scene: a value outside the grid,
        a case of a batched scene, a batch of an unbatched one or past the seeds, a name not among the files, each
        named with what the scene has."""
        block = self.study_block(w.scene, "contact")
        case, batch = _CASE.fullmatch(w.group), _BATCH.fullmatch(w.group)
        named = SimpleNamespace(scene=w.scene, topography=w.group)
        if self.scene_source(w.scene).stem != CASE_STEM:  # a patch source: its named cases
            if case or batch:
                self.generated_block(w.scene, "contact")  # says the scene's cases are named by file
            self.check_topography(named, "contact")
            return ContactGroup("named", w.group, (w.group,), block)
        size = batch_size(block)
        if case is None and batch is None:
            blocks = " nor ".join(f"{s.key} block" for s in SOURCES.values() if issubclass(s, PatchSource))
            stem = (f"{CONTACT_BATCH_STEM}.nc (its seeds in batches of {size}: contact.solver.batch)" if size > 1
                    else f"{CASE_STEM}.nc")
            raise WorkflowError(f"scene {w.scene!r} has no {blocks}, so it has no named case {w.group!r}; its "
                                f"contact files are named {stem}")
        found = case or batch
        self.check_grid_values(SimpleNamespace(scene=w.scene, **{k: found[k] for k in ("k_l", "k_s", "H")}),
                               "contact")
        if case is not None:
            return self._one_case(w, case, block, size)
        if size == 1:
            raise WorkflowError(f"scene {w.scene!r} solves each contact case alone (contact.solver.batch is 1), so it "
                                f"has no contact batch files; its cases are results/{w.scene}/contact/{CASE_STEM}.nc")
        n_batches = -(-block["seeds"] // size)
        index = batch["batch"]
        if index != str(int(index)) or int(index) >= n_batches:
            raise WorkflowError(f"scene {w.scene!r}, contact: batch {index} of {w.group} is not one of the scene's "
                                f"batches 0..{n_batches - 1} ({block['seeds']} seeds in batches of {size}; written "
                                "without leading zeros)")
        group = ContactBatch(batch["k_l"], batch["k_s"], batch["H"], int(index),
                             batch_seeds(int(index), size, block["seeds"]))
        return ContactGroup("batch", w.group, tuple(group.cases), block)

    @staticmethod
    def _one_case(w, case, block: Mapping, size: int) -> ContactGroup:
        """The group of one generated case (in one process or over ranks); a case of a batched scene is named with
        its batch's file."""
        seed = case["seed"]
        check_seed(w.scene, "contact", seed, block["seeds"])
        if size > 1:
            stem = CONTACT_BATCH_STEM.format(k_l=case["k_l"], k_s=case["k_s"], H=case["H"],
                                             batch=batch_index(seed, size))
            raise WorkflowError(f"scene {w.scene!r} solves its seeds in batches of {size} (contact.solver.batch), so "
                                f"case {w.group} has no file of its own: it is a group of "
                                f"results/{w.scene}/contact/{stem}.nc")
        ranks = ranks_of(block)
        return ContactGroup("ranks" if ranks > 1 else "case", w.group,
                            (Case(case["k_l"], case["k_s"], case["H"], int(seed)),), block, ranks)

    def contact_input(self, w) -> list[str]:
        """The surfaces of a contact job's cases, in the order of its solve."""
        return [f"results/{w.scene}/surfaces/{stem}.nc" for stem in self.contact_group(w).stems]

    def contact_params(self, provider):
        """A params function: ``provider``'s values of the scene's contact block, once the job's group is checked."""
        return lambda w: provider(self.contact_group(w).block)

    def contact_surface_params(self, provider):
        """A params function: what a job's surfaces were made with: ``provider`` of the contact block (generated),
        or the named case's reader settings (a patch source's)."""

        def values(w):
            group = self.contact_group(w)
            if group.kind == "named":
                return self.scene_source(w.scene).reader_settings(self.scenes[w.scene], group.stem)
            return provider(group.block)

        return values

    def contact_kind(self, w) -> str:
        """A params function: what the job solves, :attr:`ContactGroup.kind` (``case``, ``ranks``, ``batch``,
        ``named``)."""
        return self.contact_group(w).kind

    def contact_cases(self, w) -> list[dict]:
        """A params function: the group's cases in the order of its solve, as the wildcards of a case's file:
        ``{k_l, k_s, H, seed}`` each (generated), or ``{topography: name}``."""
        group = self.contact_group(w)
        if group.kind == "named":
            return [{"topography": group.stem}]
        return [{"k_l": c.k_l, "k_s": c.k_s, "H": c.H, "seed": str(c.seed)} for c in group.members]

    def contact_threads(self, w) -> int:
        """Cores of a contact job: its ranks for a case over ranks (locally; ``profiles/slurm`` sets one CPU a task),
        else 1."""
        return self.contact_group(w).ranks

    def contact_tasks(self, w) -> int | None:
        """The ``tasks`` resource of a contact job: its MPI processes (SLURM's ``--ntasks``) for a case over ranks;
        none for a job in one process (Snakemake drops a resource that is None), whose group job's resources would
        otherwise add up the tasks of its jobs."""
        group = self.contact_group(w)
        return group.ranks if group.kind == "ranks" else None

    def contact_mpi(self, w) -> int | None:
        """The ``mpi`` resource of a contact job: 1 for a case over ranks, none for a job in one process.

        Its presence makes a job an MPI job to the SLURM executor (one allocation of ``tasks`` tasks, the job's
        script run once inside it) and nothing else reads it: the command that starts the ranks is the rule's own
        ``launcher`` resource (``mpiexec``; ``srun`` under ``profiles/slurm``), which a one-process job carries
        unread, since a profile sets resources per rule, not per job.
        """
        return 1 if self.contact_group(w).kind == "ranks" else None

    def contact_bundle(self, w) -> str | None:
        """The rule's ``group``: :data:`BUNDLE` (``profiles/slurm`` packs such jobs into one SLURM job), none for a job
        over MPI ranks. Snakemake ignores groups in local runs."""
        return None if self.contact_group(w).kind == "ranks" else BUNDLE

    def contact_job_mem_mb(self, w) -> int:
        """Peak memory of one contact job [MB]: one case's (:func:`contact_mem_mb`), a batch's, all ranks' of a case
        over ranks, or a named case's (from its file's size)."""
        group = self.contact_group(w)
        block = group.block
        if group.kind == "named":
            return self.measured_mem_mb(SimpleNamespace(scene=w.scene, topography=group.stem))
        if group.kind == "batch":
            return contact_batch_mem_mb(block["surface"]["N"], batch_size(block))
        if group.kind == "ranks":
            return contact_mpi_mem_mb(block["surface"]["N"], group.ranks)
        return contact_mem_mb(map_side(block["surface"]))

    def contact_job_mem_mb_per_cpu(self, w, threads: int = 1) -> int | None:
        """The ``mem_mb_per_cpu`` resource of a contact job over MPI ranks [MB]: :meth:`contact_job_mem_mb` (all
        ranks together) over its CPUs, ``ranks x threads``, rounded up; none for a job in one process.

        The SLURM executor asks ``--mem-per-cpu`` for it in place of ``--mem``, which SLURM grants per node: a job
        whose ranks span several nodes would otherwise ask each node for the memory of all (358 GiB a node for the
        ``cmc-32768`` scene's 128 ranks). ``threads`` is the job's (1 under ``profiles/slurm``; Snakemake passes it),
        so that the CPUs asked for, times this, are the job's memory whatever a profile sets.
        """
        group = self.contact_group(w)
        if group.kind != "ranks":
            return None
        return mpi_mem_mb_per_cpu(self.contact_job_mem_mb(w), group.ranks, threads)

    def contact_job_runtime_min(self, w) -> int:
        """Wall-time request of one contact job [min], by its kind as :meth:`contact_job_mem_mb`
        (:data:`NAMED_RUNTIME_MIN` for a named case)."""
        group = self.contact_group(w)
        block = group.block
        if group.kind == "named":
            return NAMED_RUNTIME_MIN
        n_steps = block["load"]["n_steps"]
        if group.kind == "batch":
            return contact_batch_runtime_min(block["surface"]["N"], n_steps, batch_size(block))
        if group.kind == "ranks":
            return contact_mpi_runtime_min(block["surface"]["N"], n_steps, group.ranks)
        return contact_runtime_min(map_side(block["surface"]), n_steps)

    def contact_members_of(self, scene: str) -> list[list]:
        """Where each contact case of ``scene`` is, in the order of its cases (the aggregate's ``cases``):
        ``[file, group]``, the group ``None`` for a file of one case, the case's stem in a batch's file."""
        block = self.study_block(scene, "contact")
        if self.scene_source(scene).stem != CASE_STEM or batch_size(block) == 1:
            stems = self.scene_source(scene).stems(self.scenes[scene], "contact")
            return [[f"results/{scene}/contact/{stem}.nc", None] for stem in stems]
        return [[f"results/{scene}/contact/{b.stem}.nc", case.stem] for b in contact_batches(block) for case in b.cases]

    def contact_files(self, scene: str) -> list[str]:
        """Every contact job's file of ``scene``, once each (the aggregate's input)."""
        return list(dict.fromkeys(path for path, _ in self.contact_members_of(scene)))

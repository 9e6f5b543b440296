"""A generated study's cases: the ``k_l x k_s x H x seeds`` grid of a study block, and their file stems.

Kept apart from :mod:`.config` so that the surface sources (:mod:`.sources`), which the config's
validation asks, can use them without importing the validation back.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

#: File stem of one case: the config's own strings for k_l, k_s, H and the seed.
CASE_STEM = "kl{k_l}_ks{k_s}_H{H}_s{seed}"


#: File stem of one representativity batch: every k_s and seed of one (k_l, H) in one file.
BATCH_STEM = "kl{k_l}_H{H}"

#: File stem of one contact batch (``contact.solver.batch`` > 1): the seeds ``b B .. (b + 1) B - 1`` of one
#: ``(k_l, k_s, H)``, solved together (:func:`contact_batches`).
CONTACT_BATCH_STEM = "kl{k_l}_ks{k_s}_H{H}_b{batch}"


@dataclass(frozen=True)
class Case:
    """One surface realisation: cutoffs and Hurst exponent as config strings, and a seed."""

    k_l: str
    k_s: str
    H: str
    seed: int

    @property
    def stem(self) -> str:
        """File stem ``kl{k_l}_ks{k_s}_H{H}_s{seed}`` built from the config strings."""
        return CASE_STEM.format(k_l=self.k_l, k_s=self.k_s, H=self.H, seed=self.seed)


def batches(block: dict) -> list[tuple[str, str]]:
    """The ``(k_l, H)`` batches of a study block's grid: one representativity job each."""
    grid = block["grid"]
    return list(itertools.product(grid["k_l"], grid["H"]))


def cases(block: dict) -> list[Case]:
    """All cases of a study block: k_l x k_s x H x seeds (seeds 0..seeds-1)."""
    grid = block["grid"]
    return [
        Case(kl, ks, h, seed)
        for kl, ks, h in itertools.product(grid["k_l"], grid["k_s"], grid["H"])
        for seed in range(block["seeds"])
    ]


def batch_size(block: dict) -> int:
    """The cases a contact job solves together: ``solver.batch`` of a validated contact block (absent: 1)."""
    return int(block["solver"].get("batch", 1))


@dataclass(frozen=True)
class ContactBatch:
    """Cases of one grid and one load schedule solved in one job: seeds ``seeds`` of one ``(k_l, k_s, H)``.

    Attributes
    ----------
    k_l, k_s, H : str
        The cases' cutoffs and Hurst exponent, as config strings.
    index : int
        The batch's number among its ``(k_l, k_s, H)``'s: it holds seeds ``index B .. (index + 1) B - 1``.
    seeds : tuple of int
        Its seeds, increasing (fewer than ``B`` in the last batch when ``B`` does not divide the seeds).
    """

    k_l: str
    k_s: str
    H: str
    index: int
    seeds: tuple[int, ...]

    @property
    def stem(self) -> str:
        """File stem ``kl{k_l}_ks{k_s}_H{H}_b{index}``."""
        return CONTACT_BATCH_STEM.format(k_l=self.k_l, k_s=self.k_s, H=self.H, batch=self.index)

    @property
    def cases(self) -> list[Case]:
        """Its cases, in seed order (the order of the batch's solve and of its file's groups)."""
        return [Case(self.k_l, self.k_s, self.H, seed) for seed in self.seeds]


def batch_seeds(index: int, size: int, n_seeds: int) -> tuple[int, ...]:
    """The seeds of batch ``index`` of ``size`` when a ``(k_l, k_s, H)`` has seeds 0..n_seeds-1 (empty past them).

    Batches are fixed chunks of the seeds (0..B-1, B..2B-1, ...), not a partition of however many
    seeds there are: a batch's seeds depend only on ``index`` and ``size``, cut at ``n_seeds``, so a
    new seed changes only the batch it falls in and every earlier batch keeps its cases (and its job).
    """
    if size < 1 or index < 0:
        raise ValueError(f"a batch needs size >= 1 and index >= 0, got size={size!r}, index={index!r}")
    return tuple(range(index * size, min((index + 1) * size, n_seeds)))


def batch_index(seed: int, size: int) -> int:
    """The batch that holds ``seed`` when batches hold ``size`` seeds each (:func:`batch_seeds`)."""
    return int(seed) // int(size)


def contact_batches(block: dict) -> list[ContactBatch]:
    """The batches of a contact block's cases: every ``(k_l, k_s, H)``'s seeds in chunks of ``solver.batch``.

    Cases of one ``(k_l, k_s, H)`` share the grid (every case of a generated scene has N and L of its
    ``surface`` block) and the load schedule (a batched scene's loads are relative to E*, the same for
    every case: :func:`roughcontact.pipeline.config.checks.check_batch`), so each chunk of seeds can be
    solved together. With ``solver.batch: 1`` every case is a batch of its own.
    """
    size, n_seeds = batch_size(block), block["seeds"]
    grid = block["grid"]
    return [
        ContactBatch(kl, ks, h, index, batch_seeds(index, size, n_seeds))
        for kl, ks, h in itertools.product(grid["k_l"], grid["k_s"], grid["H"])
        for index in range(-(-n_seeds // size))
    ]


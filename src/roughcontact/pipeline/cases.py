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


def is_adhesive(block: dict) -> bool:
    """Whether a validated contact block asks for adhesion (``effects.adhesion``).

    An adhesive study draws the load cycle and the pull-off instead of the contact evolution law:
    its fit and the non-adhesive theory curves are neither run nor drawn (``figures.adhesion``).
    """
    return "adhesion" in block.get("effects", {})

"""The ``generated`` source: synthetic surfaces by FFT filtering (:mod:`roughcontact.surfaces.synthetic`).

The source of every scene that names no other (no source block): each study block's ``surface``,
``grid`` and ``seeds`` give the ``k_l x k_s x H x seeds`` cases (:mod:`roughcontact.pipeline.cases`), one
surface each by the ``surface`` / ``surface_rep`` rules (``generate_surface.py``); representativity
runs in ``(k_l, H)`` batches that make their surfaces in memory. Periodic boundary by default;
fitted per ``(k_l, k_s, H)`` over seeds (``fit_cel``); the grid figures.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping

from ...analysis.aggregate import CASE_DIMS, add_derived, combine_cases, representativity_statistics, seed_statistics
from ..cases import BATCH_STEM, CASE_STEM, batch_size, batches, cases, contact_batches
from ..config.checks import check_grid
from ..config.schema import STUDIES
from ..datasets import split_cases
from .base import SOURCES, Source, register


@register
class Generated(Source):
    """Surfaces made by the generator from each study block's grid and seeds."""

    name = "generated"
    key = None
    case_keys = ("k_l", "k_s", "H", "seed")
    stem = CASE_STEM
    case_dims = tuple(CASE_DIMS)
    record_key = "surface"
    fit = "grid"
    figures = "grid"
    surface_rules = ("surface", "surface_rep", "representativity")
    studies = ("representativity", "contact", "accuracy", "kappa_gap")

    @classmethod
    def applies(cls, scene: Mapping) -> bool:
        """A scene with no other source's block."""
        return not any(other.key in scene for other in SOURCES.values() if other.key)

    @classmethod
    def check_scene(cls, name: str, scene: dict, delta: Mapping | None = None, *, check_files: bool = True) -> dict:
        out = copy.deepcopy(scene)
        for study in STUDIES:
            if study in out:
                check_grid(name, study, out[study], ((delta or {}).get(study) or {}) if delta is not None else None)
        if "contact" in out:
            out["contact"]["solver"].setdefault("boundary", cls.default_boundary)
        return out

    @classmethod
    def cases(cls, scene: Mapping, study: str) -> list[dict]:
        return [{"k_l": c.k_l, "k_s": c.k_s, "H": c.H, "seed": c.seed} for c in cases(scene[study])]

    @classmethod
    def batch_stems(cls, scene: Mapping, study: str) -> list[str]:
        return [BATCH_STEM.format(k_l=kl, H=h) for kl, h in batches(scene[study])]

    @staticmethod
    def aggregate(datasets, paths, cases, kind="contact"):
        """The per-case datasets on the grid of their cases (``cases``: ``[k_l, k_s, H, seed]`` each),
        with the statistics over seeds."""
        expected = [(float(kl), float(ks), float(h), int(s)) for kl, ks, h, s in cases]
        ds = combine_cases(datasets, paths, expected=expected, kind=kind)
        if kind == "contact":
            ds = add_derived(ds)
            return ds.merge(seed_statistics(ds))
        return ds.merge(representativity_statistics(ds))

    @staticmethod
    def unbatch(path: str, ds) -> list[tuple]:
        """A representativity batch's cases (every k_s and seed of one (k_l, H)), each with its label."""
        return [(one, f"{path} (k_s {one.k_s.values[0]:g}, seed {int(one.seed.values[0])})")
                for one in split_cases(ds)]

    @classmethod
    def plan(cls, scene: Mapping) -> list[str]:
        parts = []
        if "representativity" in scene:
            rep = scene["representativity"]
            parts.append(f"{len(cases(rep))} representativity surfaces at {_grid(rep)} in {len(batches(rep))} jobs")
        if "contact" in scene:
            con = scene["contact"]
            n_cases, n_steps = len(cases(con)), con["load"]["n_steps"]
            parts.append(f"{n_cases} contact cases x {n_steps} load steps = {n_cases * n_steps} solves at {_grid(con)}")
            if batch_size(con) > 1:
                parts[-1] += (f", in {len(contact_batches(con))} batches of up to {batch_size(con)} cases "
                              "(contact.solver.batch)")
        return parts


def _grid(block: Mapping) -> str:
    """A study's grid in the plan's words: ``N=1024`` (maps), ``profiles of N=4096 points`` (surface.dimension 1)."""
    n = block["surface"]["N"]
    return f"profiles of N={n} points" if block["surface"].get("dimension") == 1 else f"N={n}"

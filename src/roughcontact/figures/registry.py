"""The figure registry: every figure the workflow can draw, by name.

One generic Snakemake rule (``workflow/rules/figures.smk``) makes
``results/{scene}/figures/{figure}.{png,pdf}`` for any name registered here, as
rna-seq-star-deseq2 makes ``pca.{variable}.svg`` from one rule. A :class:`FigureSpec` says
which scene block the figure needs, which files it reads, how it is drawn and where its
report caption lives. A new figure is one entry here and one caption file in
``workflow/report/``.

A scene gets the figures of the kind its surface source draws (:mod:`roughcontact.pipeline.sources`,
``Source.figures``): a patch source's scene (measured, array, ...: its cases are files named by
strings) the figures with ``cases="patches"`` (:mod:`roughcontact.figures.measured`), a generated
scene those with ``cases="grid"``: the generator's figures index cases by ``(k_l, k_s, H, seed)``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import xarray as xr
from matplotlib.figure import Figure

from ..pipeline.case import contact_effects, follows_elastic_law
from ..pipeline.cases import CASE_STEM, cases as grid_cases
from ..pipeline.io import read_dataset
from ..pipeline.sources import source_of
from . import measured as plots_measured
from .accuracy import fig_accuracy
from .adhesion import HYSTERESIS_VARIABLES, PULL_OFF_VARIABLES, fig_hysteresis, fig_pull_off
from .area_load import fig_area_load
from .contact_map import CONTACT_MAP_VARIABLES, MAP_CASES, fig_contact_maps
from .dpbar import fig_dpbar
from .kappa import fig_kappa
from .representativity import fig_representativity, fig_surface_examples

#: Paths an input role may name: one file or a list of files.
Paths = str | list[str]


@dataclass(frozen=True)
class FigureSpec:
    """One figure of the workflow.

    Attributes
    ----------
    study : str
        The scene block the figure needs (``representativity``, ``contact``, ``accuracy``); for a
        ``measured`` figure the study it belongs to, while ``wanted`` decides.
    inputs : callable
        ``inputs(block) -> {role: path or [paths]}`` from the validated study block (the whole
        validated scene for ``cases="patches"``), paths relative to ``results/{scene}/``.
    render : callable
        ``render({role: path or [paths]}) -> Figure``: reads the files, draws the figure.
    category : str
        Section of the Snakemake report.
    caption : str
        Caption file (reStructuredText) in ``workflow/report/``.
    wanted : callable
        ``wanted(block) -> bool``: whether a scene with this study block asks for the figure;
        ``wanted(scene)`` for ``cases="patches"``.
    cases : str
        The kind of scene it draws: ``"grid"`` (generated cases) or ``"patches"`` (a patch
        source's named files), matched against the scene source's ``figures``. A patches figure's
        ``inputs`` and ``wanted`` take the whole scene: the patches' names live outside the study
        blocks, and the topography maps are made for whichever study the scene has.
    """

    study: str
    inputs: Callable[[Mapping], dict[str, Paths]]
    render: Callable[[Mapping[str, Paths]], Figure]
    category: str
    caption: str
    wanted: Callable[[Mapping], bool] = lambda block: True
    cases: str = "grid"

    @property
    def whole_scene(self) -> bool:
        """Whether ``inputs`` and ``wanted`` take the whole scene (a patches figure) or a study block."""
        return self.cases == "patches"

    def input_paths(self, scene: Mapping) -> dict[str, Paths]:
        """Input files by role for the validated ``scene``, relative to ``results/{scene}/``."""
        return self.inputs(scene if self.whole_scene else scene[self.study])

    def asked_by(self, scene: Mapping) -> bool:
        """Whether the validated ``scene`` asks for this figure."""
        if self.cases != source_of(scene).figures:
            return False
        if self.whole_scene:
            return bool(self.wanted(scene))
        return self.study in scene and bool(self.wanted(scene[self.study]))


def _contact_inputs(block: Mapping) -> dict[str, Paths]:
    return {"agg": "aggregate/contact.nc", "fit": "fit/cel.nc"}


def _contact_figure(draw: Callable) -> Callable[[Mapping[str, Paths]], Figure]:
    def render(paths: Mapping[str, Paths]) -> Figure:
        agg = read_dataset(paths["agg"], stage="aggregate", variables=["area_fraction"])
        return draw(agg, agg, read_dataset(paths["fit"], stage="fit"))

    return render


def _render_representativity(paths: Mapping[str, Paths]) -> Figure:
    return fig_representativity(read_dataset(paths["rep"], stage="aggregate", variables=["epsilon"]))


def _example_inputs(block: Mapping) -> dict[str, Paths]:
    """Seed 0 and the first H of each example pair (the paper's Fig. 1 b-d)."""
    h = block["grid"]["H"][0]
    stems = [CASE_STEM.format(k_l=e["k_l"], k_s=e["k_s"], H=h, seed=0) for e in block["examples"]]
    return {"surfaces": [f"surfaces_rep/{stem}.nc" for stem in stems]}


def _render_surface_examples(paths: Mapping[str, Paths]) -> Figure:
    surfaces = [read_dataset(p, stage="surface", variables=["heights"]) for p in paths["surfaces"]]
    return fig_surface_examples([
        (s.heights.values.squeeze(), f"$k_l$ = {float(s.k_l[0]):g}, $k_s$ = {float(s.k_s[0]):g}")
        for s in surfaces
    ])


def _render_accuracy(paths: Mapping[str, Paths]) -> Figure:
    return fig_accuracy(read_dataset(paths["summary"], stage="accuracy", variables=["err_kappa"]))


# ------------------------------------------------------------------ patch sources' scenes (measured, array, ...)
def _surface_files(scene: Mapping) -> list[str]:
    """``surfaces/{name}.nc`` of every named case of a patch source's scene, by name."""
    return [f"surfaces/{name}.nc" for name in sorted(source_of(scene).names(scene))]


def _measured_contact_inputs(scene: Mapping) -> dict[str, Paths]:
    # The surfaces give each topography's grid size N for the title.
    return {"agg": "aggregate/contact.nc", "fit": "fit/cel.nc", "surfaces": _surface_files(scene)}


def _grid_sizes(paths: Sequence[str]) -> dict[str, tuple[int, int]]:
    """Grid ``(nx, ny)`` (a line scan's ``(n,)``) of each surface file by topography name, from its dimensions
    alone (a measured height map can be large, and only its size is needed)."""
    sizes = {}
    for path in paths:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            name = str(ds["topography"].values.ravel()[0]) if "topography" in ds.coords else path
            sizes[name] = tuple(int(ds.sizes[d]) for d in ("x", "y") if d in ds.sizes)  # a line scan: (n,)
    return sizes


def _measured_contact_figure(draw: Callable) -> Callable[[Mapping[str, Paths]], Figure]:
    def render(paths: Mapping[str, Paths]) -> Figure:
        agg = read_dataset(paths["agg"], stage="aggregate", variables=["area_fraction"])
        return draw(agg, read_dataset(paths["fit"], stage="fit"), sizes=_grid_sizes(paths["surfaces"]))

    return render


def _render_topographies(paths: Mapping[str, Paths]) -> Figure:
    return plots_measured.fig_topographies(
        [read_dataset(p, stage="surface", variables=["heights"]) for p in paths["surfaces"]])


# ------------------------------------------------------------------ adhesive scenes
#: Most cases :func:`fig_hysteresis` draws (seed 0 of each group, or each file, in order).
HYSTERESIS_CASES = 8


def _hysteresis_inputs(block: Mapping) -> dict[str, Paths]:
    """Seed 0 of each ``(k_l, k_s, H)`` with ``k_l < k_s``, at most :data:`HYSTERESIS_CASES`."""
    stems = [c.stem for c in grid_cases(block) if c.seed == 0 and float(c.k_l) < float(c.k_s)]
    return {"cases": [f"contact/{stem}.nc" for stem in stems[:HYSTERESIS_CASES]]}


def _patch_hysteresis_inputs(scene: Mapping) -> dict[str, Paths]:
    return {"cases": [f"contact/{name}.nc" for name in sorted(source_of(scene).names(scene))][:HYSTERESIS_CASES]}


def _render_hysteresis(paths: Mapping[str, Paths]) -> Figure:
    cases = []
    for path in paths["cases"]:
        ds = read_dataset(path, stage="contact", variables=list(HYSTERESIS_VARIABLES))
        cases.append((Path(path).stem, ds))
    return fig_hysteresis(cases)


def _render_pull_off(paths: Mapping[str, Paths]) -> Figure:
    agg = read_dataset(paths["agg"], stage="aggregate", variables=list(PULL_OFF_VARIABLES))
    dims = ("topography",) if "topography" in agg.dims else ("k_l", "k_s", "H", "seed")
    return fig_pull_off(agg, dims)


# ------------------------------------------------------------------ stored fields (outputs.fields)
def _stores_fields(block: Mapping) -> bool:
    """Whether a contact block asks for the pressure and gap fields of some steps (``outputs.fields``)."""
    return bool(block.get("outputs", {}).get("fields"))


def _case_files(stems: Sequence[str]) -> dict[str, Paths]:
    """Each case's surface (its heights) and contact file (its fields), in the same order."""
    return {"surfaces": [f"surfaces/{s}.nc" for s in stems], "contact": [f"contact/{s}.nc" for s in stems]}


def _contact_map_inputs(block: Mapping) -> dict[str, Paths]:
    """Seed 0 of each ``(k_l, k_s, H)``, at most :data:`~.contact_map.MAP_CASES`: a few cases, one figure."""
    return _case_files([c.stem for c in grid_cases(block) if c.seed == 0][:MAP_CASES])


def _patch_contact_map_inputs(scene: Mapping) -> dict[str, Paths]:
    return _case_files(sorted(source_of(scene).names(scene))[:MAP_CASES])


def _render_contact_maps(paths: Mapping[str, Paths]) -> Figure:
    return fig_contact_maps([(read_dataset(s, stage="surface", variables=["heights"]),
                              read_dataset(c, stage="contact", variables=list(CONTACT_MAP_VARIABLES)))
                             for s, c in zip(paths["surfaces"], paths["contact"], strict=True)])


def _patch_scene_stores_fields(scene: Mapping) -> bool:
    return "contact" in scene and _stores_fields(scene["contact"])


def _brought(figure: str):
    """``wanted`` of a figure a contact block's effects bring (:attr:`roughcontact.solver.effects.Effect.figures`)."""
    return lambda block: any(figure in effect.figures for effect in contact_effects(block))


def _brought_to_scene(figure: str):
    """``wanted`` of a patch scene's figure its contact study's effects bring."""
    return lambda scene: "contact" in scene and _brought(figure)(scene["contact"])


def _elastic_scene(scene: Mapping) -> bool:
    return "contact" in scene and follows_elastic_law(scene["contact"])


FIGURES: dict[str, FigureSpec] = {
    "representativity": FigureSpec(
        "representativity", lambda block: {"rep": "aggregate/representativity.nc"}, _render_representativity,
        "Representativity", "representativity.rst"),
    "surface_examples": FigureSpec(
        "representativity", _example_inputs, _render_surface_examples, "Representativity",
        "surface_examples.rst", wanted=lambda block: bool(block["examples"])),
    # the CEL and the theories of Fig. 2 describe contact without adhesion: only where the effects keep the law
    "area_load": FigureSpec(
        "contact", _contact_inputs, _contact_figure(fig_area_load), "Contact", "area_load.rst",
        wanted=follows_elastic_law),
    "kappa": FigureSpec("contact", _contact_inputs, _contact_figure(fig_kappa), "Contact", "kappa.rst",
                        wanted=follows_elastic_law),
    "dpbar": FigureSpec("contact", _contact_inputs, _contact_figure(fig_dpbar), "Contact", "dpbar.rst",
                        wanted=follows_elastic_law),
    # the figures an effect brings (Effect.figures: an adhesive scene's load cycle and pull-off)
    "hysteresis": FigureSpec("contact", _hysteresis_inputs, _render_hysteresis, "Adhesion", "hysteresis.rst",
                             wanted=_brought("hysteresis")),
    "pull_off": FigureSpec("contact", lambda block: {"agg": "aggregate/contact.nc"}, _render_pull_off, "Adhesion",
                           "pull_off.rst", wanted=_brought("pull_off")),
    # only where the scene stores fields (outputs.fields): the maps of a few cases at those steps
    "contact_map": FigureSpec("contact", _contact_map_inputs, _render_contact_maps, "Contact", "contact_map.rst",
                              wanted=_stores_fields),
    "accuracy": FigureSpec(
        "accuracy", lambda block: {"summary": "accuracy/summary.nc"}, _render_accuracy, "Accuracy", "accuracy.rst"),
    # Patch sources' scenes: every scene has the topography maps; the contact figures need a contact study.
    "topographies": FigureSpec(
        "representativity", lambda scene: {"surfaces": _surface_files(scene)}, _render_topographies,
        "Topographies", "topographies.rst", wanted=lambda scene: True, cases="patches"),
    "measured_area_load": FigureSpec(
        "contact", _measured_contact_inputs, _measured_contact_figure(plots_measured.fig_measured_area_load),
        "Contact", "measured_area_load.rst", wanted=_elastic_scene, cases="patches"),
    "measured_kappa": FigureSpec(
        "contact", _measured_contact_inputs, _measured_contact_figure(plots_measured.fig_measured_kappa),
        "Contact", "measured_kappa.rst", wanted=_elastic_scene, cases="patches"),
    "measured_contact_map": FigureSpec(
        "contact", _patch_contact_map_inputs, _render_contact_maps, "Contact", "contact_map.rst",
        wanted=_patch_scene_stores_fields, cases="patches"),
    "measured_hysteresis": FigureSpec(
        "contact", _patch_hysteresis_inputs, _render_hysteresis, "Adhesion", "hysteresis.rst",
        wanted=_brought_to_scene("hysteresis"), cases="patches"),
    "measured_pull_off": FigureSpec(
        "contact", lambda scene: {"agg": "aggregate/contact.nc"}, _render_pull_off, "Adhesion", "pull_off.rst",
        wanted=_brought_to_scene("pull_off"), cases="patches"),
}


def scene_figures(scene: Mapping) -> list[str]:
    """Names of the registered figures a validated scene asks for, in registry order."""
    return [name for name, spec in FIGURES.items() if spec.asked_by(scene)]

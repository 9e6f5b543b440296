"""What the workflow's rules ask of a scene: file patterns, wildcard checks, input and params functions, resources.

The rules (``workflow/rules/*.smk``) stay declarative: each input, params or resources entry is a function
of this module, bound to the validated config once in ``workflow/rules/common.smk``::

    TARGETS = Targets.from_config(config, accuracy_variants=variants, figures=FIGURES)
    case_input = TARGETS.case_input
    ...

A :class:`Targets` holds the validated scenes (the config is validated once, here: the Snakefile checks
only that each config file is YAML). Its ``check_*`` methods stop a requested file whose wildcards are
not in its scene with a :class:`~snakemake.exceptions.WorkflowError` naming the wildcard, its value and
the scene's allowed values; its ``*_input``, ``*_params`` and ``*_files`` methods build what Snakemake
calls with a job's wildcards. The resource formulas (:func:`surface_mem_mb`, ...) are plain functions of N.

Wildcard constraints (:data:`WILDCARD_CONSTRAINTS`) fix only the shape of a file name, never the values a
scene allows: any target of the right shape reaches its rule, whose input function then names a wrong
value with the scene's allowed ones (constraints built from the configured values would leave
Snakemake's bare ``MissingRuleException`` instead).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

from snakemake.exceptions import WorkflowError

from .case import follows_elastic_law
from .cases import BATCH_STEM, CASE_STEM
from .config import ConfigError, load_schema
from .contact_jobs import (  # noqa: F401 (the rules' resource formulas)
    ContactJobs,
    check_seed,
    contact_mem_mb,
    contact_path,
    contact_runtime_min,
    map_side,
)
from .scenes import validate_config
from .sources import SOURCES, PatchSource, source_of

#: A grid value (k_l, k_s, H) in a file name: the config's own text, holding no ``_`` or ``/``.
GRID_VALUE = r"[^_/]+"
#: A named case (wildcard ``topography``) never looks like a generated case's or batch's file
#: (:mod:`roughcontact.pipeline.measured` refuses such names in the config).
NOT_GENERATED = r"(?!kl[^_/]*(?:_ks[^_/]*)?_H[^_/]*(?:_s\d+)?\.[^./]+$)"
#: The shapes of the wildcards: they keep file names unambiguous and nothing more.
WILDCARD_CONSTRAINTS = {
    "scene": r"[A-Za-z][A-Za-z0-9_-]*",
    "k_l": GRID_VALUE,
    "k_s": GRID_VALUE,
    "H": GRID_VALUE,
    "seed": r"\d+",
    "batch": r"\d+",
    "variant": r"[^/]+",
    "figure": r"[A-Za-z0-9_-]+",
    "topography": NOT_GENERATED + r"[A-Za-z0-9][A-Za-z0-9._-]*",
    # a contact job's group: one case's stem, a batch's or a named case's (roughcontact.pipeline.contact_jobs)
    "group": r"[A-Za-z0-9][A-Za-z0-9._-]*",
}


# ------------------------------------------------------------------------------ file patterns
def case_path(folder: str, ext: str = "nc") -> str:
    """Pattern of one case's file: ``results/{scene}/<folder>/kl{k_l}_ks{k_s}_H{H}_s{seed}.<ext>``."""
    return f"results/{{scene}}/{folder}/{CASE_STEM}.{ext}"


def batch_path(folder: str, ext: str = "nc") -> str:
    """Pattern of one batch's file (every k_s and seed of a k_l, H): ``results/{scene}/<folder>/kl{k_l}_H{H}.<ext>``."""
    return f"results/{{scene}}/{folder}/{BATCH_STEM}.{ext}"


def topography_path(folder: str, ext: str = "nc") -> str:
    """Pattern of one named case's file (a patch source's): ``results/{scene}/<folder>/{topography}.<ext>``."""
    return f"results/{{scene}}/{folder}/{{topography}}.{ext}"


# ------------------------------------------------------------------------------ resources
def surface_mem_mb(n: int) -> int:
    """Peak memory of one surface job [MB]: interpreter + libraries (~250 MB) + ~10 N^2 doubles."""
    return int(250 + 10 * 8 * n * n / 2**20)


def surface_runtime_min(n: int) -> int:
    """Wall-time request of a surface or representativity job [min]: ~2 s at N=1024, x100 margin."""
    return max(5, int(5 * (n / 1024) ** 2))


def batch_runtime_min(block: Mapping) -> int:
    """Wall-time request of a representativity job [min]: ~0.15 s a surface at N=1024, x20 margin."""
    n, surfaces = map_side(block["surface"]), block["seeds"] * len(block["grid"]["k_s"])
    return max(5, int(0.05 * surfaces * (n / 1024) ** 2))


def file_mem_mb(path) -> int:
    """Peak memory of a job on one named case's file [MB]: interpreter + ~160 doubles per stored value.

    The grid size is only known once the file is read; a file stores at least 2 bytes a point,
    and the free-boundary solver works on the 2n x 2n padded grid (4x the periodic ~40 doubles).
    """
    points = Path(path).stat().st_size / 2
    return int(300 + 160 * 8 * points / 2**20)


# ------------------------------------------------------------------------------ wildcard errors
def not_allowed(scene: str, where: str, key: str, value: str, allowed) -> WorkflowError:
    """The error for wildcard ``key`` = ``value`` outside ``allowed`` (the scene's own strings).

    A value equal as a number to an allowed one (``H=0.80`` for ``0.8``) is named: file names carry
    the config's text verbatim.
    """
    msg = f"scene {scene!r}, {where}: wildcard {key}={value} is not in the scene; allowed: {', '.join(allowed)}"
    try:
        same = [a for a in allowed if float(a) == float(value)]
    except ValueError:
        same = []
    if same:
        msg += f" (file names carry the config's text verbatim: write {key}={same[0]})"
    return WorkflowError(msg)


def check_one_case(w, block: Mapping, study: str) -> None:
    """Stop unless the wildcards' k_l, k_s and H are those of a one-case study block (accuracy, kappa_gap)."""
    for key, allowed in (("k_l", [block["k_l"]]), ("k_s", [block["k_s"]]), ("H", block["H"])):
        if getattr(w, key) not in allowed:
            raise not_allowed(w.scene, f"{study}.{key}", key, getattr(w, key), allowed)


def one_case_stem(block: Mapping, h: str, seed: int) -> str:
    """File stem of one case of a one-case study block (accuracy, kappa_gap) at Hurst exponent ``h``."""
    return CASE_STEM.format(k_l=block["k_l"], k_s=block["k_s"], H=h, seed=seed)


# ------------------------------------------------------------------------------ the scenes
class Targets(ContactJobs):
    """The validated scenes of a config, and every function the rules call with a job's wildcards.

    Parameters
    ----------
    valid : Mapping
        :func:`~roughcontact.pipeline.scenes.validate_config`'s result: ``scenes`` (each validated),
        ``scene`` (the one that runs) and ``invalid`` (each invalid scene's message).
    accuracy_variants : callable
        The accuracy study's settings of a block (:func:`roughcontact.studies.accuracy.variants`), given
        here because the study sits above the pipeline's layer.
    figures : mapping
        The registered figures by name (:data:`roughcontact.figures.registry.FIGURES`: each with
        ``asked_by(scene)`` and ``input_paths(scene)``), given here for the same reason: the figures
        draw the pipeline's files and sit beside it, so the pipeline does not import them.

    Attributes
    ----------
    scenes : dict
        Every valid scene by name.
    active : str
        The scene that runs (``--config scene=NAME``).
    invalid : dict
        The message of each invalid scene: a target under ``results/<it>/`` stops with it.
    """

    def __init__(self, valid: Mapping, accuracy_variants: Callable[[Mapping], list[dict]], figures: Mapping):
        self.scenes = valid["scenes"]
        self.active = valid["scene"]
        self.invalid = valid["invalid"]
        self.accuracy_variants = accuracy_variants
        self.figures = figures

    @classmethod
    def from_config(cls, config: Mapping, accuracy_variants: Callable[[Mapping], list[dict]],
                    figures: Mapping) -> Targets:
        """The targets of ``config`` (Snakemake's ``config``), validated once: a ``WorkflowError`` if invalid."""
        try:
            valid = validate_config(config, load_schema())
        except ConfigError as err:
            raise WorkflowError(f"invalid config: {err}") from None
        return cls(valid, accuracy_variants, figures)

    # -------------------------------------------------------------------------- scenes and blocks
    def scene_of(self, name: str) -> dict:
        """The validated scene called ``name`` (a job's ``scene`` wildcard), or a clear error."""
        if name in self.invalid:
            raise WorkflowError(f"invalid config: {self.invalid[name]}")
        if name not in self.scenes:
            raise WorkflowError(
                f"wildcard scene={name}: no scene {name!r} in the config; defined scenes: {', '.join(self.scenes)}"
            )
        return self.scenes[name]

    def scene_source(self, name: str):
        """The surface source of scene ``name`` (:mod:`roughcontact.pipeline.sources`)."""
        return source_of(self.scene_of(name))

    def patch_names(self, name: str) -> list[str]:
        """The named cases of scene ``name`` (a patch source's files), sorted; [] for a generated scene."""
        return self.scene_source(name).names(self.scenes[name])

    def study_block(self, scene: str, study: str) -> dict:
        """The validated config block of ``study`` in ``scene``, or a clear error."""
        block = self.scene_of(scene).get(study)
        if block is None:
            raise WorkflowError(f"scene {scene!r} declares no '{study}' block, so it has no {study} outputs")
        return block

    def generated_block(self, scene: str, study: str) -> dict:
        """The study block of a scene whose cases are the generator's; a patch source's cases are its files."""
        block = self.study_block(scene, study)
        src = self.scene_source(scene)
        if src.stem != CASE_STEM:
            raise WorkflowError(
                f"scene {scene!r} runs on {src.name} surfaces: its {study} cases are named by {src.key} file "
                f"(results/{scene}/<stage>/<name>.nc), not kl.._ks.._H.._s..; allowed names: "
                f"{', '.join(src.names(self.scenes[scene]))}"
            )
        return block

    def keeps_surfaces(self, study: str) -> bool:
        """Whether the active scene keeps the surfaces of ``study`` (its ``keep_surfaces``, default true)."""
        return self.scenes[self.active].get(study, {}).get("keep_surfaces", True)

    # -------------------------------------------------------------------------- generated cases
    def check_grid_values(self, wildcards, study: str, keys=("k_l", "k_s", "H")) -> dict:
        """Stop with the allowed values if a requested file's ``keys`` wildcards are not in the scene's grid; else
        the study's block."""
        block = self.generated_block(wildcards.scene, study)
        grid = block["grid"]
        for key in keys:
            if getattr(wildcards, key) not in grid[key]:
                raise not_allowed(wildcards.scene, f"{study}.grid.{key}", key, getattr(wildcards, key), grid[key])
        return block

    def check_case(self, wildcards, study: str) -> dict:
        """Stop with the allowed values if a requested case is not in the scene's grid; else its block."""
        block = self.check_grid_values(wildcards, study)
        check_seed(wildcards.scene, study, wildcards.seed, block["seeds"])
        return block

    def check_batch(self, wildcards, study: str) -> dict:
        """Stop with the allowed values if a requested batch's k_l or H is not in the scene's grid; else its block."""
        return self.check_grid_values(wildcards, study, ("k_l", "H"))

    def case_input(self, study: str, folder: str | None = None):
        """An input function: the job's case checked against the scene's grid (a clear error if it is
        not there), then the case's file in ``folder`` (no input without one)."""

        def inputs(w):
            self.check_case(w, study)
            if folder is None:
                return []
            return f"results/{w.scene}/{folder}/{CASE_STEM.format(k_l=w.k_l, k_s=w.k_s, H=w.H, seed=w.seed)}.nc"

        return inputs

    def batch_input(self, study: str):
        """An input function (no input): the job's batch checked against the scene's grid."""

        def inputs(w):
            self.check_batch(w, study)
            return []

        return inputs

    def batch_params(self, study: str, provider):
        """A params function: ``provider``'s values for the job's study block, once the batch is checked."""
        return lambda w: provider(self.check_batch(w, study))

    def case_params(self, study: str, provider):
        """A params function: ``provider``'s values for the job's study block, once the case is checked."""
        return lambda w: provider(self.check_case(w, study))

    def study_params(self, study: str, provider):
        """A params function: ``provider``'s values for the study block of the job's scene."""
        return lambda w: provider(self.study_block(w.scene, study))

    def batch_files(self, scene: str, study: str, folder: str) -> list[str]:
        """Paths of the ``folder`` files of every batch of ``study`` in ``scene`` (a patch source: every file)."""
        self.study_block(scene, study)
        stems = self.scene_source(scene).batch_stems(self.scenes[scene], study)
        return [f"results/{scene}/{folder}/{stem}.nc" for stem in stems]

    def case_files(self, scene: str, study: str, folder: str) -> list[str]:
        """Paths of the ``folder`` files of every case of ``study`` in ``scene``, as its source names them."""
        self.study_block(scene, study)
        stems = self.scene_source(scene).stems(self.scenes[scene], study)
        return [f"results/{scene}/{folder}/{stem}.nc" for stem in stems]

    def case_list(self, study: str):
        """A params function: the scene's cases of ``study``: ``[k_l, k_s, H, seed]`` each, or a patch source's
        names."""

        def cases_of(w):
            self.study_block(w.scene, study)
            return self.scene_source(w.scene).case_list(self.scenes[w.scene], study)

        return cases_of

    # -------------------------------------------------------------------------- named cases (patch sources)
    def check_topography(self, w, study: str | None = None) -> dict:
        """The scene of a job on a named case (a patch source's), once its ``topography`` wildcard is checked
        (and its study exists)."""
        scene, src = self.scene_of(w.scene), self.scene_source(w.scene)
        if not issubclass(src, PatchSource):
            blocks = " nor ".join(f"{s.key} block" for s in SOURCES.values() if issubclass(s, PatchSource))
            raise WorkflowError(
                f"scene {w.scene!r} has no {blocks}, so it has no named case {w.topography!r}; "
                "its cases' files are named kl{k_l}_ks{k_s}_H{H}_s{seed}.nc (representativity: kl{k_l}_H{H}.nc)"
            )
        if w.topography not in src.names(scene):
            raise WorkflowError(
                f"scene {w.scene!r}: wildcard topography={w.topography} is not one of its {src.key} files; "
                f"allowed: {', '.join(src.names(scene))}"
            )
        if study is not None:
            self.study_block(w.scene, study)
        return scene

    def topography_file(self, w) -> str:
        """The file a named case's surface job reads (its input, so a changed file is read again)."""
        return self.scene_source(w.scene).input_file(self.check_topography(w), w.topography)

    def topography_input(self, folder: str, study: str):
        """An input function: the job's topography name checked against its scene, then its file in ``folder``."""

        def inputs(w):
            self.check_topography(w, study)
            return f"results/{w.scene}/{folder}/{w.topography}.nc"

        return inputs

    def topography_params(self, study: str | None = None, provider=None):
        """A params function: the reader settings of the job's file (its source's), or ``provider`` of its
        study block."""
        if provider is None:
            return lambda w: self.scene_source(w.scene).reader_settings(self.check_topography(w), w.topography)
        return lambda w: provider(self.check_topography(w, study)[study])

    def measured_mem_mb(self, w) -> int:
        """Peak memory of a job on one named case's file [MB] (:func:`file_mem_mb` of its file)."""
        return file_mem_mb(self.topography_file(w))

    # -------------------------------------------------------------------------- figures and final products
    def scene_figures(self, scene: Mapping) -> list[str]:
        """Names of the registered figures the validated ``scene`` asks for, in registry order."""
        return [name for name, spec in self.figures.items() if spec.asked_by(scene)]

    def figure_spec(self, w):
        """The registered figure named by the wildcards, if the scene asks for it."""
        figures = self.scene_figures(self.scene_of(w.scene))
        if w.figure not in self.figures:
            raise WorkflowError(
                f"scene {w.scene!r}: wildcard figure={w.figure} is not a figure of roughcontact "
                f"(roughcontact.figures.registry.FIGURES); the scene's figures: {', '.join(figures) or 'none'}"
            )
        if w.figure not in figures:
            raise WorkflowError(
                f"scene {w.scene!r} does not ask for figure {w.figure!r}; its figures: {', '.join(figures) or 'none'}"
            )
        return self.figures[w.figure]

    def figure_inputs(self, w) -> dict:
        """Input files of a figure, by role, under ``results/{scene}/``."""
        paths = self.figure_spec(w).input_paths(self.scenes[w.scene])
        root = f"results/{w.scene}"
        return {
            role: [f"{root}/{p}" for p in value] if isinstance(value, list) else f"{root}/{value}"
            for role, value in paths.items()
        }

    def scene_targets(self, scene: str) -> list[str]:
        """Final products of a scene: only what its blocks call for."""
        s = self.scenes[scene]
        out = []
        if "representativity" in s:
            out += [f"results/{scene}/aggregate/representativity.nc"]
        if "contact" in s:
            out += [f"results/{scene}/aggregate/contact.nc"]
            if follows_elastic_law(s["contact"]):  # the CEL: contact without adhesion
                out += [f"results/{scene}/fit/cel.{ext}" for ext in ("nc", "csv", "html")]
        if "accuracy" in s:
            out += [f"results/{scene}/accuracy/summary.{ext}" for ext in ("nc", "csv", "md")]
        if "kappa_gap" in s:
            out += [f"results/{scene}/kappa_gap/kappa-gap.{ext}" for ext in ("nc", "md")]
        out += [f"results/{scene}/figures/{fig}.{ext}" for fig in self.scene_figures(s)
                for ext in ("png", "pdf", "caption.rst", "record.json")]
        out += [f"results/{scene}/report/{name}.rst" for name in ("result", "summary", "figures", "run")]
        return out

    def report_figure_inputs(self, w) -> dict[str, list[str]]:
        """The scene's figures (``png``) and their captions (``caption``), in registry order, for the report's
        landing page (``report/figures.rst``)."""
        names = self.scene_figures(self.scene_of(w.scene))
        root = f"results/{w.scene}/figures"
        return {"png": [f"{root}/{n}.png" for n in names], "caption": [f"{root}/{n}.caption.rst" for n in names]}

    def run_record_inputs(self, w) -> list[str]:
        """What the run record (``report/run.rst``) waits for: every other final product of the scene, so
        that the CPU time it gives is the whole run's."""
        return [t for t in self.scene_targets(w.scene) if not t.endswith("/report/run.rst")]

    # -------------------------------------------------------------------------- one-case studies
    def accuracy_setting(self, w) -> dict:
        """The setting (N, tol, n_steps, seeds) named by the ``variant`` wildcard, or a clear error."""
        block = self.study_block(w.scene, "accuracy")
        for s in self.accuracy_variants(block):
            if s["label"] == w.variant:
                check_one_case(w, block, "accuracy")
                check_seed(w.scene, f"accuracy setting {w.variant}", w.seed, s["seeds"])
                return s
        allowed = ", ".join(s["label"] for s in self.accuracy_variants(block))
        raise WorkflowError(
            f"scene {w.scene!r}, accuracy: wildcard variant={w.variant} is not one of its settings; allowed: {allowed}"
        )

    def accuracy_input(self, w) -> list:
        """An input function (no input): the job's setting and case checked against the accuracy study."""
        self.accuracy_setting(w)
        return []

    def accuracy_files(self, scene: str, pattern: str) -> list[str]:
        """Every case file (or benchmark file) of every setting of the scene's accuracy study.

        ``pattern`` holds ``{scene}``, ``{label}`` (the setting) and ``{stem}`` (the case).
        """
        block = self.study_block(scene, "accuracy")
        return [
            pattern.format(scene=scene, label=s["label"], stem=one_case_stem(block, h, seed))
            for s in self.accuracy_variants(block)
            for h in block["H"]
            for seed in range(s["seeds"])
        ]

    def kappa_gap_setting(self, w) -> dict:
        """The kappa-gap variant named by the ``variant`` wildcard, its case checked, or a clear error."""
        block = self.study_block(w.scene, "kappa_gap")
        if w.variant not in block["variants"]:
            allowed = ", ".join(block["variants"])
            raise WorkflowError(
                f"scene {w.scene!r}, kappa_gap: wildcard variant={w.variant} is not one of its variants; "
                f"allowed: {allowed}"
            )
        check_one_case(w, block, "kappa_gap")
        setting = block["variants"][w.variant]
        check_seed(w.scene, f"kappa_gap variant {w.variant}", w.seed, setting["seeds"])
        return setting

    def kappa_gap_input(self, w) -> list:
        """An input function (no input): the job's variant and case checked against the kappa-gap study."""
        self.kappa_gap_setting(w)
        return []

    def kappa_gap_files(self, scene: str, folder: str, ext: str = "nc") -> list[str]:
        """Every case's file under ``results/{scene}/<folder>/<variant>/`` (cases, benchmarks) of the kappa-gap
        study."""
        block = self.study_block(scene, "kappa_gap")
        return [
            f"results/{scene}/{folder}/{label}/{one_case_stem(block, h, seed)}.{ext}"
            for label, v in block["variants"].items()
            for h in block["H"]
            for seed in range(v["seeds"])
        ]

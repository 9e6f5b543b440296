# Shared set-up: validate the config (every scene) before any job is planned, expose
# the scenes and their surface sources (roughcontact.pipeline.sources: the rules ask a scene's
# source for its cases, file names and readers), and check every requested file's wildcards
# against its scene (a mistyped target fails at once, naming the wildcard, its value and the
# scene's allowed values).
from pathlib import Path

from roughcontact.core.cli import one_line
from roughcontact.figures.registry import FIGURES, scene_figures
from roughcontact.pipeline import params
from roughcontact.pipeline.cases import is_adhesive
from roughcontact.pipeline.config import (
    BATCH_STEM,
    CASE_STEM,
    ConfigError,
    check_config_files,
    load_schema,
    plan_summary,
    validate_config,
)
from roughcontact.pipeline.sources import SOURCES, PatchSource, source_of
from roughcontact.pipeline.progress import write_plan
from roughcontact.studies.accuracy import variants as accuracy_variants

try:
    check_config_files(workflow.configfiles)
    _VALID = validate_config(config, load_schema())
except ConfigError as _err:
    raise WorkflowError(f"invalid config: {_err}") from None

SCENES = _VALID["scenes"]
ACTIVE_SCENE = _VALID["scene"]
# An invalid scene stops only a run of it (a target under results/<it>/ names its error); the others plan.
INVALID_SCENES = _VALID["invalid"]
for _message in INVALID_SCENES.values():
    logger.warning(f"roughcontact: {_message} (a run of that scene would stop here)")
# What the active scene computes, before any job runs (a large scene's cost at a glance).
logger.info(plan_summary(ACTIVE_SCENE, SCENES[ACTIVE_SCENE]))


# The plan each contact job's scene ETA is read against (python -m roughcontact.pipeline.progress).
onstart:
    try:
        write_plan(Path("results", ACTIVE_SCENE), ACTIVE_SCENE, SCENES[ACTIVE_SCENE], workflow.cores)
    except OSError as _err:  # a read-only or full results/<scene>: one line, before any job runs
        logger.error(
            f"roughcontact: {one_line(_err)}; the run writes under results/{ACTIVE_SCENE}/: make it writable "
            "(or free space), then run again"
        )
        raise SystemExit(1)


def case_path(folder, ext="nc"):
    """Pattern of one case's file: ``results/{scene}/<folder>/kl{k_l}_ks{k_s}_H{H}_s{seed}.<ext>``."""
    return f"results/{{scene}}/{folder}/{CASE_STEM}.{ext}"


def batch_path(folder, ext="nc"):
    """Pattern of one batch's file (every k_s and seed of a k_l, H): ``results/{scene}/<folder>/kl{k_l}_H{H}.<ext>``."""
    return f"results/{{scene}}/{folder}/{BATCH_STEM}.{ext}"


def topography_path(folder, ext="nc"):
    """Pattern of one named case's file (a patch source's: measured, array, ...): ``results/{scene}/<folder>/{topography}.<ext>``."""
    return f"results/{{scene}}/{folder}/{{topography}}.{ext}"


# Wildcard constraints fix only the shape of a file name, never the values a scene allows: any
# target of the right shape reaches its rule, whose input function (below) then names a wrong
# value with the scene's allowed ones. Constraints built from the configured values would leave
# Snakemake's bare MissingRuleException instead. The shapes keep file names unambiguous: a grid
# value holds no '_' or '/', a seed only digits, and a named case (wildcard topography) never looks
# like a generated case's or batch's file (roughcontact.pipeline.measured refuses such names in the config).
GRID_VALUE = r"[^_/]+"
NOT_GENERATED = r"(?!kl[^_/]*(?:_ks[^_/]*)?_H[^_/]*(?:_s\d+)?\.[^./]+$)"


wildcard_constraints:
    scene=r"[A-Za-z][A-Za-z0-9_-]*",
    k_l=GRID_VALUE,
    k_s=GRID_VALUE,
    H=GRID_VALUE,
    seed=r"\d+",
    variant=r"[^/]+",
    figure=r"[A-Za-z0-9_-]+",
    topography=NOT_GENERATED + r"[A-Za-z0-9][A-Za-z0-9._-]*",


def scene_of(name):
    """The validated scene called ``name`` (a job's ``scene`` wildcard), or a clear error."""
    if name in INVALID_SCENES:
        raise WorkflowError(f"invalid config: {INVALID_SCENES[name]}")
    if name not in SCENES:
        raise WorkflowError(
            f"wildcard scene={name}: no scene {name!r} in the config; defined scenes: {', '.join(SCENES)}"
        )
    return SCENES[name]


def scene_source(name):
    """The surface source of scene ``name`` (roughcontact.pipeline.sources)."""
    return source_of(scene_of(name))


def patch_names(name):
    """The named cases of scene ``name`` (a patch source's files), sorted; [] for a generated scene."""
    return scene_source(name).names(SCENES[name])


def study_block(scene, study):
    """The validated config block of `study` in `scene`, or a clear error."""
    block = scene_of(scene).get(study)
    if block is None:
        raise WorkflowError(f"scene {scene!r} declares no '{study}' block, so it has no {study} outputs")
    return block


def _not_allowed(scene, where, key, value, allowed):
    """The error for wildcard ``key`` = ``value`` outside ``allowed`` (the scene's own strings)."""
    msg = f"scene {scene!r}, {where}: wildcard {key}={value} is not in the scene; allowed: {', '.join(allowed)}"
    try:
        same = [a for a in allowed if float(a) == float(value)]
    except ValueError:
        same = []
    if same:
        msg += f" (file names carry the config's text verbatim: write {key}={same[0]})"
    return WorkflowError(msg)


def _generated_block(scene, study):
    """The study block of a scene whose cases are the generator's; a patch source's cases are its files."""
    block = study_block(scene, study)
    src = scene_source(scene)
    if src.stem != CASE_STEM:
        raise WorkflowError(
            f"scene {scene!r} runs on {src.name} surfaces: its {study} cases are named by {src.key} file "
            f"(results/{scene}/<stage>/<name>.nc), not kl.._ks.._H.._s..; allowed names: "
            f"{', '.join(src.names(SCENES[scene]))}"
        )
    return block


def check_seed(scene, where, seed, n_seeds):
    """Stop unless ``seed`` is one of the scene's seeds 0..n_seeds-1, written without leading zeros."""
    if seed != str(int(seed)) or int(seed) >= n_seeds:
        raise WorkflowError(
            f"scene {scene!r}, {where}: wildcard seed={seed} is not one of the scene's seeds 0..{n_seeds - 1} "
            "(written without leading zeros)"
        )


def check_case(wildcards, study):
    """Stop with the allowed values if a requested case is not in the scene's grid."""
    block = _generated_block(wildcards.scene, study)
    grid = block["grid"]
    for key in ("k_l", "k_s", "H"):
        if getattr(wildcards, key) not in grid[key]:
            raise _not_allowed(wildcards.scene, f"{study}.grid.{key}", key, getattr(wildcards, key), grid[key])
    check_seed(wildcards.scene, study, wildcards.seed, block["seeds"])
    return block


def check_batch(wildcards, study):
    """Stop with the allowed values if a requested batch's k_l or H is not in the scene's grid."""
    block = _generated_block(wildcards.scene, study)
    for key in ("k_l", "H"):
        if getattr(wildcards, key) not in block["grid"][key]:
            raise _not_allowed(wildcards.scene, f"{study}.grid.{key}", key, getattr(wildcards, key), block["grid"][key])
    return block


def case_input(study, folder=None):
    """An input function: the job's case checked against the scene's grid (a clear error if it is
    not there), then the case's file in ``folder`` (no input without one)."""

    def inputs(w):
        check_case(w, study)
        if folder is None:
            return []
        return f"results/{w.scene}/{folder}/{CASE_STEM.format(k_l=w.k_l, k_s=w.k_s, H=w.H, seed=w.seed)}.nc"

    return inputs


def batch_input(study):
    """An input function (no input): the job's batch checked against the scene's grid."""

    def inputs(w):
        check_batch(w, study)
        return []

    return inputs


def batch_params(study, provider):
    """A params function: ``provider``'s values for the job's study block, once the batch is checked."""
    return lambda w: provider(check_batch(w, study))


def batch_files(scene, study, folder):
    """Paths of the ``folder`` files of every batch of ``study`` in ``scene`` (a patch source: every file)."""
    study_block(scene, study)
    return [f"results/{scene}/{folder}/{stem}.nc" for stem in scene_source(scene).batch_stems(SCENES[scene], study)]


def case_files(scene, study, folder):
    """Paths of the ``folder`` files of every case of ``study`` in ``scene``, as its source names them."""
    study_block(scene, study)
    return [f"results/{scene}/{folder}/{stem}.nc" for stem in scene_source(scene).stems(SCENES[scene], study)]


def case_params(study, provider):
    """A params function: ``provider``'s values for the job's study block, once the case is checked."""
    return lambda w: provider(check_case(w, study))


def study_params(study, provider):
    """A params function: ``provider``'s values for the study block of the job's scene."""
    return lambda w: provider(study_block(w.scene, study))


def case_list(study):
    """A params function: the scene's cases of ``study``: ``[k_l, k_s, H, seed]`` each, or a patch source's names."""

    def cases_of(w):
        study_block(w.scene, study)
        return scene_source(w.scene).case_list(SCENES[w.scene], study)

    return cases_of


def check_topography(w, study=None):
    """The scene of a job on a named case (a patch source's), once its ``topography`` wildcard is checked
    (and its study exists)."""
    scene, src = scene_of(w.scene), scene_source(w.scene)
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
        study_block(w.scene, study)
    return scene


def topography_file(w):
    """The file a named case's surface job reads (its input, so a changed file is read again)."""
    return scene_source(w.scene).input_file(check_topography(w), w.topography)


def topography_input(folder, study):
    """An input function: the job's topography name checked against its scene, then its file in ``folder``."""

    def inputs(w):
        check_topography(w, study)
        return f"results/{w.scene}/{folder}/{w.topography}.nc"

    return inputs


def topography_params(study=None, provider=None):
    """A params function: the reader settings of the job's file (its source's), or ``provider`` of its study block."""
    if provider is None:
        return lambda w: scene_source(w.scene).reader_settings(check_topography(w), w.topography)
    return lambda w: provider(check_topography(w, study)[study])


def figure_spec(w):
    """The registered figure named by the wildcards, if the scene asks for it."""
    figures = scene_figures(scene_of(w.scene))
    if w.figure not in FIGURES:
        raise WorkflowError(
            f"scene {w.scene!r}: wildcard figure={w.figure} is not a figure of roughcontact "
            f"(roughcontact.figures.registry.FIGURES); the scene's figures: {', '.join(figures) or 'none'}"
        )
    if w.figure not in figures:
        raise WorkflowError(
            f"scene {w.scene!r} does not ask for figure {w.figure!r}; its figures: {', '.join(figures) or 'none'}"
        )
    return FIGURES[w.figure]


def figure_inputs(w):
    """Input files of a figure, by role, under ``results/{scene}/``."""
    spec = figure_spec(w)
    paths = spec.input_paths(SCENES[w.scene])
    root = f"results/{w.scene}"
    return {
        role: [f"{root}/{p}" for p in value] if isinstance(value, list) else f"{root}/{value}"
        for role, value in paths.items()
    }


def figure_caption(name):
    """The report caption of a registered figure (its file in workflow/report/)."""
    return Path(workflow.basedir, "workflow", "report", FIGURES[name].caption).read_text()


def scene_targets(scene):
    """Final products of a scene: only what its blocks call for."""
    s = SCENES[scene]
    out = []
    if "representativity" in s:
        out += [f"results/{scene}/aggregate/representativity.nc"]
    if "contact" in s:
        out += [f"results/{scene}/aggregate/contact.nc"]
        if not is_adhesive(s["contact"]):  # the CEL describes contact without adhesion
            out += [f"results/{scene}/fit/cel.nc", f"results/{scene}/fit/cel.csv"]
    if "accuracy" in s:
        out += [f"results/{scene}/accuracy/summary.{ext}" for ext in ("nc", "csv", "md")]
    if "kappa_gap" in s:
        out += [f"results/{scene}/kappa_gap/kappa-gap.{ext}" for ext in ("nc", "md")]
    out += expand("results/{scene}/figures/{fig}.{ext}", scene=scene, fig=scene_figures(s), ext=("png", "pdf"))
    out += [f"results/{scene}/report/summary.rst"]
    return out


def surface_mem_mb(n):
    """Peak memory of one surface job [MB]: interpreter + libraries (~250 MB) + ~10 N^2 doubles."""
    return int(250 + 10 * 8 * n * n / 2**20)


def surface_runtime_min(n):
    """Wall-time request of a surface or representativity job [min]: ~2 s at N=1024, x100 margin."""
    return max(5, int(5 * (n / 1024) ** 2))


def batch_runtime_min(block):
    """Wall-time request of a representativity job [min]: ~0.15 s a surface at N=1024, x20 margin."""
    n, surfaces = block["surface"]["N"], block["seeds"] * len(block["grid"]["k_s"])
    return max(5, int(0.05 * surfaces * (n / 1024) ** 2))


def contact_mem_mb(n):
    """Peak memory of one contact job [MB]: interpreter + libraries + ~40 N^2 doubles of solver work."""
    return int(300 + 40 * 8 * n * n / 2**20)


def contact_runtime_min(n, n_steps):
    """Wall-time request of one contact job [min]: 30 steps at N=1024 take 15-130 s (paper grid); x9 margin."""
    return max(5, int(10 * n_steps / 30 * (n / 1024) ** 2 * 2))


def measured_mem_mb(w):
    """Peak memory of a job on one named case's file [MB]: interpreter + ~160 doubles per stored value.

    The grid size is only known once the file is read; a file stores at least 2 bytes a point,
    and the free-boundary solver works on the 2n x 2n padded grid (4x the periodic ~40 doubles).
    """
    points = Path(topography_file(w)).stat().st_size / 2
    return int(300 + 160 * 8 * points / 2**20)


def maybe_temp(path, study):
    """`temp(path)` when the active scene's study sets keep_surfaces: false."""
    keep = SCENES[ACTIVE_SCENE].get(study, {}).get("keep_surfaces", True)
    return path if keep else temp(path)


def check_one_case(w, block, study):
    """Stop unless the wildcards' k_l, k_s and H are those of a one-case study block (accuracy, kappa_gap)."""
    for key, allowed in (("k_l", [block["k_l"]]), ("k_s", [block["k_s"]]), ("H", block["H"])):
        if getattr(w, key) not in allowed:
            raise _not_allowed(w.scene, f"{study}.{key}", key, getattr(w, key), allowed)


def accuracy_setting(w):
    """The setting (N, tol, n_steps, seeds) named by the `variant` wildcard, or a clear error."""
    block = study_block(w.scene, "accuracy")
    for s in accuracy_variants(block):
        if s["label"] == w.variant:
            check_one_case(w, block, "accuracy")
            check_seed(w.scene, f"accuracy setting {w.variant}", w.seed, s["seeds"])
            return s
    allowed = ", ".join(s["label"] for s in accuracy_variants(block))
    raise WorkflowError(
        f"scene {w.scene!r}, accuracy: wildcard variant={w.variant} is not one of its settings; allowed: {allowed}"
    )


def accuracy_input(w):
    """An input function (no input): the job's setting and case checked against the accuracy study."""
    accuracy_setting(w)
    return []


def accuracy_files(scene, pattern):
    """Every case file (or benchmark file) of every setting of the scene's accuracy study."""
    block = study_block(scene, "accuracy")
    return [
        pattern.format(
            scene=scene, label=s["label"], stem=CASE_STEM.format(k_l=block["k_l"], k_s=block["k_s"], H=h, seed=seed)
        )
        for s in accuracy_variants(block)
        for h in block["H"]
        for seed in range(s["seeds"])
    ]


def kappa_gap_setting(w):
    """The kappa-gap variant named by the `variant` wildcard, its case checked, or a clear error."""
    block = study_block(w.scene, "kappa_gap")
    if w.variant not in block["variants"]:
        allowed = ", ".join(block["variants"])
        raise WorkflowError(
            f"scene {w.scene!r}, kappa_gap: wildcard variant={w.variant} is not one of its variants; allowed: {allowed}"
        )
    check_one_case(w, block, "kappa_gap")
    setting = block["variants"][w.variant]
    check_seed(w.scene, f"kappa_gap variant {w.variant}", w.seed, setting["seeds"])
    return setting


def kappa_gap_input(w):
    """An input function (no input): the job's variant and case checked against the kappa-gap study."""
    kappa_gap_setting(w)
    return []


def kappa_gap_files(scene, folder, ext="nc"):
    """Every case's file under ``results/{scene}/<folder>/<variant>/`` (cases, benchmarks) of the kappa-gap study."""
    block = study_block(scene, "kappa_gap")
    return [
        f"results/{scene}/{folder}/{label}/"
        + CASE_STEM.format(k_l=block["k_l"], k_s=block["k_s"], H=h, seed=seed)
        + f".{ext}"
        for label, v in block["variants"].items()
        for h in block["H"]
        for seed in range(v["seeds"])
    ]

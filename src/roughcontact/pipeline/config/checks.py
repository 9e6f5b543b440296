"""The cross-field rules of a scene that a schema cannot express, one check per study block.
"""

from __future__ import annotations

import functools
import importlib.util
import itertools
from collections.abc import Mapping

from ...surfaces.linescan import MIN_PROFILE_POINTS
from ..case import contact_effects
from .files import ConfigError


def _duplicates_by_value(texts) -> list[str]:
    """Strings of ``texts`` that equal an earlier one as numbers ("2" and "2.0")."""
    seen, dups = {}, []
    for text in texts:
        value = float(text)
        if value in seen:
            dups.append(f"{seen[value]!r} and {text!r}")
        seen.setdefault(value, text)
    return dups


#: The largest ``surface.N`` one process makes and solves: about 50 GB of one process's solver work at N = 16384
#: (docs/cluster.md). The schema allows N up to 65536 for contact cases split over ``contact.solver.ranks``.
MAX_ONE_PROCESS_N = 16384


def check_grid(scene: str, study: str, block: dict, written: Mapping | None = None) -> None:
    """Cross-field rules of a generated study's grid (k_l < k_s <= N/2, 0 < H < 1, examples, seeds, a profile's N,
    N above :data:`MAX_ONE_PROCESS_N` only for contact maps split over MPI ranks).

    ``written``: the study block as the scene writes it (before the merge over ``defaults``); a message about a
    field it does not hold says the value came from the ``defaults`` block.
    """
    def fail(field, msg):
        top = field.split("[")[0].split(".")[0]
        origin = " (value from the 'defaults' block)" if written is not None and top not in written else ""
        raise ConfigError(f"scene {scene!r}, field '{study}.{field}'{origin}: {msg}")

    n = block["surface"]["N"]
    if n > MAX_ONE_PROCESS_N:
        _check_beyond_one_process(fail, study, block)
    grid = block["grid"]
    for key in ("k_l", "k_s", "H"):
        for text in grid[key]:
            if float(text) <= 0:
                fail(f"grid.{key}", f"{text!r} must be > 0")
        dups = _duplicates_by_value(grid[key])
        if dups:
            fail(f"grid.{key}", f"{dups[0]} are the same number: each case would be computed twice")
    for text in grid["H"]:
        if not 0.0 < float(text) < 1.0:
            fail("grid.H", f"{text!r} is outside the allowed range 0 < H < 1")
    for text in grid["k_s"]:
        if float(text) > n / 2:
            fail("grid.k_s", f"{text!r} exceeds N/2 = {n / 2:g} (the Nyquist mode of N = {n})")
    # Every pair is run, so a pair with k_l >= k_s is an error rather than a silent skip.
    for kl, ks in itertools.product(grid["k_l"], grid["k_s"]):
        if float(kl) >= float(ks):
            fail("grid.k_l", f"k_l={kl} must be < k_s={ks} for every pair of the grid")
    for i, ex in enumerate(block.get("examples", [])):
        if ex["k_l"] not in grid["k_l"] or ex["k_s"] not in grid["k_s"]:
            fail(f"examples[{i}]", f"({ex['k_l']}, {ex['k_s']}) is not in the grid's k_l x k_s "
                                   f"({', '.join(grid['k_l'])} x {', '.join(grid['k_s'])}); pick pairs of the grid, or "
                                   f"write examples: [] in the scene's {study} block to draw none")
        if float(ex["k_l"]) >= float(ex["k_s"]):
            fail(f"examples[{i}]", f"k_l={ex['k_l']} must be < k_s={ex['k_s']}")
    if block["surface"].get("dimension") == 1 and block.get("examples"):
        fail("examples", f"draws maps of surfaces, and surface.dimension: 1 makes profiles; write examples: [] in "
                         f"the scene's {study} block")
    if block["surface"].get("dimension") == 1 and n < MIN_PROFILE_POINTS:
        fail("surface.N", f"a profile of {n} points is too short to fit or resolve (a profile needs at least "
                          f"{MIN_PROFILE_POINTS}, as a measured line scan does); set surface.N >= {MIN_PROFILE_POINTS}")
    if study == "contact" and block["seeds"] < 2:
        fail("seeds", f"{block['seeds']} is too few: the contact study's CEL fit resamples seeds and needs "
                      "at least 2")


def _check_beyond_one_process(fail, study: str, block: Mapping) -> None:
    """``surface.N`` above :data:`MAX_ONE_PROCESS_N`: allowed only for a contact study's maps over ranks > 1 (each rank
    holds its slab of rows: :mod:`roughcontact.solver.mpi`); whatever else holds a whole surface is refused."""
    n, most = block["surface"]["N"], MAX_ONE_PROCESS_N
    if block["surface"].get("dimension") == 1:
        fail("surface.N", f"{n} is above {most}, the most points of a profile (one process solves it); lower surface.N")
    if study != "contact":
        fail("surface.N", f"{n} is above {most}: the {study} study makes and analyses each whole surface in one "
                          f"process (about 50 GB of work at N = {most}); lower surface.N")
    if block["solver"].get("ranks", 1) == 1:
        fail("surface.N", f"{n} is above {most}, the largest map one process solves (about 50 GB of solver work at "
                          f"N = {most}, docs/cluster.md); split each case over MPI ranks with contact.solver.ranks, "
                          "or lower surface.N")


def check_contact(scene: str, block: dict) -> None:
    """Cross-field rules of a contact block: output steps, load schedule, effects."""
    def fail(field, msg):
        raise ConfigError(f"scene {scene!r}, field 'contact.{field}': {msg}")

    steps = block["load"]["n_steps"]
    bad = [s for s in block["outputs"]["fields"] if s > steps]
    if bad:
        fail("outputs.fields", f"steps {bad} exceed load.n_steps = {steps} (allowed 1..{steps})")
    effects = contact_effects(block)
    _check_effects(fail, block, effects)
    _check_outputs(fail, block, effects)
    if block.get("surface", {}).get("dimension") == 1:
        check_profile_contact(scene, block, "surface.dimension: 1 makes profiles")
    backend = block["solver"].get("array_backend", "numpy")
    if backend != "numpy" and block["effects"]:
        fail("solver.array_backend", f"{backend!r} runs the elastic solver only, not the effects "
                                     f"({', '.join(block['effects'])}); remove it (numpy) or the effects")
    load = block["load"]
    if "p_min" in load and load["schedule"] != "geometric":
        fail("load.p_min", f"only used by load.schedule: geometric (here {load['schedule']!r}); remove it")
    _check_final_load(fail, block, effects)
    if "target_area" in load:
        _check_target_area(fail, load)
        if "surface" in block:  # the generator's N x N grid, or N points of a profile
            n = block["surface"]["N"]
            profile = block["surface"].get("dimension") == 1
            check_target_nodes(scene, load, n if profile else n**2, f"the N = {n} {'profile' if profile else 'grid'}")
        return
    if "p_min" in load and not load["p_min"] < load["p_max"]:
        fail("load.p_min", f"{load['p_min']:g} must be < load.p_max = {load['p_max']:g}")
    relative = load.get("relative_to", "e_star")
    if relative == "e_star" and load["p_max"] > 1:
        fail("load.p_max", f"{load['p_max']:g} is p0/E* (load.relative_to: e_star) and must be <= 1")


def check_batch(scene: str, block: dict, source: str | None) -> None:
    """``solver.batch`` of a contact block: what a batch of cases cannot do, refused before any job is planned.

    A batch (:func:`roughcontact.solver.solve_contact_batch`) solves cases of one grid under one load
    schedule with the periodic elastic iteration and reports per-step columns only, so a batched block
    must have generated surfaces (``source`` None: the generator), loads relative to E* (the same for
    every case), the periodic boundary, no effects and no stored fields, clusters or P(p). ``batch: 1``
    is the unbatched default and is dropped, so that writing it changes no job's parameters.
    """
    solver = block["solver"]
    size = solver.get("batch", 1)
    if size == 1:
        solver.pop("batch", None)
        return

    def fail(field, msg):
        raise ConfigError(f"scene {scene!r}, field 'contact.{field}': {msg} (contact.solver.batch: {size} solves "
                          f"{size} cases together); {remedy(field)}")

    def remedy(field):
        if field == "solver.batch":
            return "remove solver.batch (each file alone)"
        return f"remove {field} or solver.batch (each case alone)"

    if source is not None:
        fail("solver.batch", f"batches generated cases of one grid, and a {source} scene's cases are files of their "
                             "own sizes and loads")
    load, outputs = block["load"], block["outputs"]
    if "target_area" in load:
        fail("load.target_area", "is searched on each case's own surface, so the cases' loads differ")
    if load.get("relative_to", "e_star") != "e_star":
        fail("load.relative_to", f"{load['relative_to']!r} scales each case's loads with its own rms slope, so "
                                 "the cases' loads differ (a batch runs one load schedule)")
    if solver["boundary"] != "periodic":
        fail("solver.boundary", f"{solver['boundary']!r}: a batch runs the periodic half-space only")
    if block["effects"]:
        fail("effects", f"{', '.join(block['effects'])}: a batch runs the elastic solver without effects")
    if outputs["fields"]:
        fail("outputs.fields", f"steps {outputs['fields']}: a batch stores no pressure or gap fields")
    if outputs["clusters"]:
        fail("outputs.clusters", "needs each step's contact mask, which a batch does not keep")
    if "pressure_distribution" in outputs:
        fail("outputs.pressure_distribution", "needs each step's pressure field, which a batch does not keep")


def check_ranks(scene: str, block: dict, source: str | None) -> None:
    """``solver.ranks`` of a contact block: what a case over MPI ranks cannot do, refused before any job is planned.

    A case over ranks (:func:`roughcontact.case.run_case` with ``ranks`` > 1) is solved by
    :mod:`roughcontact.solver.mpi`: a generated map (``source`` None) split in slabs of rows along x, the periodic
    elastic iteration on numpy, per-step columns only. So a block with ``ranks`` > 1 has no batch, effects, free
    boundary, CuPy, stored fields, clusters, P(p), full-contact load or ``target_area``, and at most one rank per
    row of the grid. ``ranks: 1`` is the default and is dropped, so that writing it changes no job's parameters.
    Whether MPI is installed is checked for the scene that runs (:func:`check_mpi`).
    """
    solver = block["solver"]
    ranks = solver.get("ranks", 1)
    if ranks == 1:
        solver.pop("ranks", None)
        return

    def fail(field, msg):
        remedy = "remove solver.ranks (one process)" if field == "solver.ranks" else \
            f"remove {field} or solver.ranks (one process)"
        raise ConfigError(f"scene {scene!r}, field 'contact.{field}': {msg} (contact.solver.ranks: {ranks} splits "
                          f"each case over {ranks} MPI processes); {remedy}")

    if source is not None:
        fail("solver.ranks", f"splits generated maps, and a {source} scene's cases are files solved whole (run "
                             "one over ranks with python -m roughcontact.solver.mpi --surface FILE)")
    surface = block["surface"]  # a generated scene's generator block, defaults filled
    if surface.get("dimension") == 1:
        fail("surface.dimension", "1 makes profiles, and the MPI solver splits maps")
    if ranks > surface["N"]:
        fail("solver.ranks", f"{ranks} ranks for the N = {surface['N']} grid's {surface['N']} rows along x: each "
                             f"rank needs at least one row (at most {surface['N']})")
    if solver.get("batch", 1) != 1:
        fail("solver.batch", f"{solver['batch']}: a batch solves several cases in one process, ranks one case "
                             "over several")
    if solver["boundary"] != "periodic":
        fail("solver.boundary", f"{solver['boundary']!r}: the MPI solver runs the periodic half-space only (the "
                                "free boundary's padded grid is not split)")
    if solver.get("array_backend", "numpy") != "numpy":
        fail("solver.array_backend", f"{solver['array_backend']!r}: the MPI solver runs on numpy")
    if block["effects"]:
        fail("effects", f"{', '.join(block['effects'])}: the MPI solver runs the elastic solver without effects")
    if "target_area" in block["load"]:
        fail("load.target_area", "is searched by solving the case again and again in one process")
    outputs = block["outputs"]
    if outputs["fields"]:
        fail("outputs.fields", f"steps {outputs['fields']}: a case over ranks stores no fields (a whole field on "
                               "one process is what the split avoids)")
    if outputs["clusters"]:
        fail("outputs.clusters", "labels each step's whole contact mask in one process")
    if "pressure_distribution" in outputs:
        fail("outputs.pressure_distribution", "needs each step's whole pressure field in one process")
    if outputs.get("full_contact_load"):
        fail("outputs.full_contact_load", "transforms the whole surface in one process")


def check_mpi(scene: str, contact: Mapping) -> None:
    """``solver.ranks`` > 1 on a Python that cannot import mpi4py: refused before any job (the scene that runs).

    Only the import is checked here (the launcher, ``mpiexec`` or ``srun``, is found by the job:
    :func:`roughcontact.case.mpi_command`).
    """
    ranks = contact["solver"].get("ranks", 1)
    if ranks > 1 and importlib.util.find_spec("mpi4py") is None:
        raise ConfigError(f"scene {scene!r}, field 'contact.solver.ranks': {ranks} MPI ranks need mpi4py and an MPI "
                          "runtime, which this Python cannot import; install them with `pip install "
                          "'roughcontact[mpi]'`, or remove solver.ranks (one process)")


def check_profile_contact(scene: str, block: Mapping, why: str) -> None:
    """What the 1-D (plane-strain) solver and the profiles' outputs cannot do, refused naming the key (``why``: what
    makes the scene's cases profiles): contact clusters (the labelling of a map's 4-connected nodes), adhesion and
    batches (refused by the 1-D solver)."""
    def fail(field, msg):
        raise ConfigError(f"scene {scene!r}, field 'contact.{field}': {msg} ({why}); remove it")

    if block["outputs"].get("clusters"):
        fail("outputs.clusters", "labels a map's contact clusters; a profile's contact spots are intervals, counted by "
                                 "contact_perimeter (interval ends per length)")
    for effect in contact_effects(block):
        if effect.needs_gap_iteration:
            fail(f"effects.{effect.name}", f"the gap iteration of {effect.contact_name or effect.name} solves maps "
                                           "only")
    if block["solver"].get("batch", 1) != 1:
        fail("solver.batch", "a batch of surfaces solves maps only")


def _check_effects(fail, block: dict, effects) -> None:
    """Each effect's own rules (:class:`~roughcontact.solver.effects.Effect`): against the other effects and the
    boundary, and against a generated scene's grid (known before any job; a file's grid: its patch source)."""
    names = [effect.name for effect in effects]
    boundary = block["solver"].get("boundary", "periodic")
    surface = block.get("surface", {})
    for effect in effects:
        effect_fail = functools.partial(_fail_effect, fail, effect.name)
        effect.check_config(effect_fail, others=[n for n in names if n != effect.name], boundary=boundary)
        if "N" in surface and "L" in surface:  # a generated surface: its N x N grid on L
            n, length = int(surface["N"]), float(surface["L"])
            effect.check_grid(block["solver"]["e_star"], length, (n, n), f"L / N = {surface['L']:g} / {surface['N']}",
                              effect_fail, n_field="surface.N", most_n=MAX_ONE_PROCESS_N)


def _check_outputs(fail, block: dict, effects) -> None:
    """The observables that hold only for some problems: P(p) for compressive contact, the exact full contact."""
    outputs = block["outputs"]
    tensile = [effect.name for effect in effects if effect.adds_tension]
    if "pressure_distribution" in outputs and tensile:
        fail("outputs.pressure_distribution", f"bins compressive pressures only, and {tensile[0]} adds tension; "
                                              f"remove it or effects.{tensile[0]}")
    if outputs.get("full_contact_load"):
        if block["solver"]["boundary"] != "periodic":
            fail("outputs.full_contact_load", "the exact full-contact load is that of a periodic cell; "
                                              "remove it or set solver.boundary: periodic")
        if effects:
            fail("outputs.full_contact_load", f"is the elastic solution's, not with effects "
                                              f"({', '.join(block['effects'])}); remove it or the effects")


def _fail_effect(fail, name: str, field: str, msg: str) -> None:
    fail(f"effects.{name}{field}", msg)


def _check_target_area(fail, load: dict) -> None:
    """A ``load.target_area`` block: the final load is found per case (:func:`resolve_load` dropped p_max)."""
    if "p_min" in load:
        fail("load.p_min", "not used with load.target_area: the geometric schedule then starts at "
                           "(final load) / n_steps; remove it")


#: Fewest contact nodes a ``load.target_area`` may ask for: the search stops within 1.5 nodes
#: (:func:`roughcontact.case.loading.pressure_for_area`), 10 % of 15 nodes.
MIN_TARGET_NODES = 15


def check_target_nodes(scene: str, load: Mapping, n_nodes: int, what: str) -> None:
    """Refuse a ``load.target_area`` smaller than :data:`MIN_TARGET_NODES` nodes of a map of ``n_nodes`` (``what``)."""
    target = load.get("target_area")
    if target is not None and target * n_nodes < MIN_TARGET_NODES:
        raise ConfigError(
            f"scene {scene!r}, field 'contact.load.target_area': {target:g} of the {n_nodes} nodes of {what} is "
            f"{target * n_nodes:.3g} node(s); the load search stops within 1.5 nodes, so a target below "
            f"{MIN_TARGET_NODES} nodes ({MIN_TARGET_NODES / n_nodes:.3g} here) cannot be met: raise it or the grid")


def check_against_fit(scene: str, contact: Mapping, fit: Mapping) -> None:
    """A ``target_area`` below the fit window's low end leaves the CEL fit without a load step: refuse it."""
    target, low = contact["load"].get("target_area"), fit["window"][0]
    if target is not None and target < low:
        raise ConfigError(f"scene {scene!r}, field 'contact.load.target_area': {target:g} is below fit.window's low "
                          f"end {low:g}, so no load step (every one at A/A0 <= {target:g}) would enter the CEL fit; "
                          "raise it or lower fit.window")


def check_backend(scene: str, contact: Mapping) -> None:
    """``solver.array_backend: cupy`` on a Python that cannot import CuPy: refused before any job (the scene that runs).

    Only the import is checked here: on a cluster the jobs may run on GPU nodes the submit host lacks, and a job
    without a GPU stops with the backend's own message.
    """
    backend = contact["solver"].get("array_backend", "numpy")
    if backend == "cupy" and importlib.util.find_spec("cupy") is None:
        raise ConfigError(f"scene {scene!r}, field 'contact.solver.array_backend': 'cupy' needs CuPy, which this "
                          "Python cannot import; install it with `pip install roughcontact[gpu]` (a CUDA GPU "
                          "runs the jobs), or remove array_backend (numpy)")


def _check_final_load(fail, block: dict, effects) -> None:
    """The final load against each effect's rule (:meth:`~roughcontact.solver.effects.Effect.check_final_load`)
    where it is known before any job: ``load.p_max`` relative to E*, or times the generator's rms slope."""
    load = block["load"]
    if not effects or "target_area" in load:
        return
    p_max, e_star = load["p_max"], block["solver"]["e_star"]
    if load.get("relative_to", "e_star") == "e_star":
        final, words = p_max, f"load.p_max = {p_max:g}"
    else:  # relative to the rms slope: the generator's, when it sets one (a file's: its patch source; else the job)
        slope = block.get("surface", {}).get("rms_slope")
        if slope is None:
            return
        final = p_max * slope
        words = (f"the final load p0/E* = load.p_max x surface.rms_slope = {p_max:g} x {slope:g} = {final:g} "
                 "(load.relative_to: rms_slope)")
    for effect in effects:
        effect.check_final_load(final * e_star, e_star, words, functools.partial(_fail_effect, fail, effect.name))


#: A measured scene's final load when it says nothing: p0 / (E* h') = 0.05, the paper's regime
#: (about 10 % contact on its surfaces; p0/E* = 0.005 at their h' = 0.1).
MEASURED_P_MAX = 0.05


def resolve_load(scene: str, load: dict, given: Mapping, measured: bool) -> None:
    """Fill ``load.relative_to`` in place from what the scene wrote (``given``: its own ``contact.load``).

    With ``target_area`` the final load is found per case, and ``p_max`` (inherited) is dropped. A
    measured scene that writes neither ``relative_to`` nor a load gets ``p_max: 0.05`` relative to
    each file's rms slope; one that writes ``p_max`` or ``p_min`` without ``relative_to`` is asked
    which it means, since the same number means a load ten times larger or smaller on a typical file.
    """
    def fail(field, msg):
        raise ConfigError(f"scene {scene!r}, field 'contact.{field}': {msg}")

    if "target_area" in load:
        for key in ("p_max", "relative_to"):
            if key in given:
                fail(f"load.{key}", f"not used with load.target_area (the final load is the one that gives "
                                    f"A/A0 = {load['target_area']:g} on each case); remove one of them")
            load.pop(key, None)
        return
    if measured and "relative_to" not in given:
        for key in ("p_max", "p_min"):
            if key in given:
                fail(f"load.{key}", "a measured (topography or array) scene's load is relative to each file's rms "
                                    "slope unless it says otherwise: add load.relative_to: rms_slope (the value is "
                                    "p0/(E* h'), the paper's pbar) or load.relative_to: e_star (p0/E*)")
        load["relative_to"], load["p_max"] = "rms_slope", MEASURED_P_MAX
    load.setdefault("relative_to", "e_star")
    if load["relative_to"] == "rms_slope" and "p_max" not in given:
        load["p_max"] = MEASURED_P_MAX  # the default 0.005 is p0/E*; relative to h' the paper's regime is 0.05


def _study_failure(scene: str, study: str):
    """A function raising the ConfigError of one field of a study block."""
    def fail(field, msg):
        raise ConfigError(f"scene {scene!r}, field '{study}.{field}': {msg}")

    return fail


def _check_one_case(block: dict, fail) -> float:
    """The cutoffs and H list of a one-case study (accuracy, kappa_gap); returns k_s."""
    k_l, k_s = float(block["k_l"]), float(block["k_s"])
    if not k_l < k_s:
        fail("k_l", f"k_l={block['k_l']} must be < k_s={block['k_s']}")
    for text in block["H"]:
        if not 0.0 < float(text) < 1.0:
            fail("H", f"{text!r} is outside the allowed range 0 < H < 1")
    dups = _duplicates_by_value(block["H"])
    if dups:
        fail("H", f"{dups[0]} are the same number: each case would be computed twice")
    return k_s


def check_accuracy(scene: str, block: dict) -> None:
    """Cross-field rules of an accuracy block (its one case inside the grid, axes and seeds ordered)."""
    fail = _study_failure(scene, "accuracy")
    k_s = _check_one_case(block, fail)
    settings = [("reference", block["reference"]), ("defaults", block["defaults"])]
    settings += [(f"axes.{axis}", {axis: v}) for axis, vals in block["axes"].items() for v in vals]
    for where, setting in settings:
        if "N" in setting and k_s > int(setting["N"]) / 2:
            fail(where, f"N={setting['N']} is too coarse for k_s={block['k_s']} (needs N >= {2 * k_s:g})")
        if "tol" in setting and not 0.0 < float(setting["tol"]) < 1.0:
            fail(where, f"tol={setting['tol']} is outside the allowed range 0 < tol < 1")
        if "n_steps" in setting and int(setting["n_steps"]) < 1:
            fail(where, f"n_steps={setting['n_steps']} must be >= 1")
    if max(int(s) for s in block["seed_axis"]) < 1:
        fail("seed_axis", "needs at least one entry >= 1")


def check_kappa_gap(scene: str, block: dict) -> None:
    """Cross-field rules of a kappa_gap block (its one case inside the grid, each variant's settings)."""
    fail = _study_failure(scene, "kappa_gap")
    k_s = _check_one_case(block, fail)
    variants = block["variants"]
    for label, v in variants.items():
        if k_s > int(v["N"]) / 2:
            fail(f"variants.{label}.N", f"N={v['N']} is too coarse for k_s={block['k_s']} (needs N >= {2 * k_s:g})")
        if not 0.0 < float(v["tol"]) < 1.0:
            fail(f"variants.{label}.tol", f"tol={v['tol']} is outside the allowed range 0 < tol < 1")
    roles = [v["role"] for v in variants.values()]
    if roles.count("baseline") != 1:
        fail("variants", f"needs exactly one variant with role: baseline, got {roles.count('baseline')}")
    if 0 < roles.count("resolution") < 3:
        fail("variants", "a continuum series (role: resolution) needs at least three N")
    sk = [v for v in variants.values() if v["role"] == "solver" and v["method"] == "stanley-kato"]
    refs = {v["N"] for v in variants.values() if v["role"] == "solver" and v["method"] == "bem"}
    for v in sk:
        if v["N"] not in refs:
            fail("variants", f"a Stanley & Kato variant at N={v['N']} needs a role: solver variant with method: bem "
                             "at the same N to be compared with")

"""Stage 3: solve the contact of one surface (generated or measured) over the scene's load steps."""
from functools import partial
from pathlib import Path

import numpy as np

from roughcontact.analysis.stiffness import stiffness_variable
from roughcontact.pipeline.datasets import contact_dataset, contact_observers, full_contact_variable, surface_heights
from roughcontact.pipeline.io import eta, read_dataset, run_logged, write_dataset
from roughcontact.pipeline.loading import case_loads
from roughcontact.pipeline.params import recorded, require_made_for
from roughcontact.pipeline.progress import scene_progress
from roughcontact.pipeline.sources import for_case
from roughcontact.solver import effects_from_config, solve_contact, step_notes


def case_of(w) -> dict:
    """The job's case: its wildcards but the scene (a generated case's k_l, k_s, H, seed; a named case's topography)."""
    return {key: getattr(w, key) for key in w.keys() if key != "scene"}


def labels_of(case: dict) -> dict:
    """The case as roughcontact.pipeline.datasets' keyword arguments."""
    return {"hurst" if key == "H" else key: value for key, value in case.items()}


def main(log):
    w, settings = snakemake.wildcards, snakemake.params.settings
    case = case_of(w)
    surf = read_dataset(snakemake.input[0], stage="surface", variables=["heights", "rms_slope", "alpha"])
    # a surface records what it was made with under its source's key (generator block, reader settings)
    require_made_for(surf, snakemake.input[0], case, **{for_case(case).record_key: snakemake.params.surface})
    heights, length = surface_heights(surf, snakemake.input[0])
    solver = settings["solver"]
    solve = partial(
        solve_contact,
        heights,
        e_star=solver["e_star"],
        length=length,
        tol=solver["tol"],
        max_iter=solver["max_iter"],
        threads=snakemake.threads,
        effects=effects_from_config(settings["effects"], e_star=solver["e_star"]),
        boundary=solver["boundary"],
        array_backend=solver.get("array_backend", "numpy"),
        # both a generator block and a reader's settings name the study's length unit
        length_unit=snakemake.params.surface["unit"],
        pressure_unit=solver["pressure_unit"],
    )
    rms_slope = float(surf.rms_slope.squeeze())
    name = Path(snakemake.output[0]).stem  # the case, at the start of its warnings
    loads, load_info = case_loads(settings, rms_slope, heights.size, solve, log, name=name)

    spent = []

    def progress(step, p0, area, iterations, converged, seconds):
        # one line per load step as it goes (the log handler flushes every record), with what is left
        spent.append(seconds)
        log.info("step %d/%d: p0 = %.6g, A/A0 = %.6g, %d iterations, %.2f s%s; %s", step, len(loads), p0, area,
                 iterations, seconds, "" if converged else ", NOT converged", eta(spent, len(loads)))

    result = solve(
        loads,
        store_fields=settings["outputs"]["fields"] or False,
        clusters=settings["outputs"]["clusters"],
        progress=progress,
        observers=contact_observers(settings["outputs"], solver["e_star"] * rms_slope),
    )
    if settings["outputs"].get("stiffness"):
        result["contact_stiffness"] = stiffness_variable(result, snakemake.params.surface["unit"],
                                                         solver["pressure_unit"])
    if settings["outputs"].get("full_contact_load"):
        result["full_contact_pressure"] = full_contact_variable(heights, length, solver["e_star"],
                                                                result["pressure"].attrs["units"])
    ds = contact_dataset(result, rms_slope=rms_slope, alpha=float(surf.alpha.squeeze()),
                         e_star=solver["e_star"], **labels_of(case))
    ds.attrs.update(load_info)
    for note in step_notes(result):
        log.warning("%s: %s", name, note)
    unconverged = int((~result.converged.values).sum())
    if unconverged:
        log.warning("%s: %d of %d load steps did not converge to tol=%g (max residual %.3g); "
                    "they are flagged in the output's 'converged' variable",
                    name, unconverged, result.sizes["step"], solver["tol"], float(result.residual.max()))
    write_dataset(ds, snakemake.output[0], stage="contact", scene=w.scene,
                  scene_parameters={**recorded(surf), **settings})
    log.info("contact %s: A/A0 %.4g -> %.4g, %d iterations in %.2f s", snakemake.output[0],
             float(result.area_fraction[0]), float(result.area_fraction[-1]),
             int(result.iterations.sum()), float(np.sum(result.wall_time)))
    scene = scene_progress(Path(snakemake.output[0]).parents[1])  # results/{scene}
    if scene is not None:
        log.info(scene[1].text(scene[0]))


run_logged(snakemake.log[0], main)

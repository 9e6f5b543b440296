"""Stage 3: solve one contact job's group over the scene's load steps and write its file once: one surface
(generated or measured), one surface over contact.solver.ranks MPI processes, or a batch of seeds
(contact.solver.batch > 1: one NetCDF group a case). roughcontact.pipeline.contact_jobs says which."""
from pathlib import Path

import numpy as np

from roughcontact.case import run_case
from roughcontact.pipeline.case import check_case_loads, contact_case
from roughcontact.pipeline.datasets import contact_dataset, surface_grid, surface_heights
from roughcontact.pipeline.io import lazy_dataset, read_dataset, run_logged, write_dataset, write_groups
from roughcontact.pipeline.params import recorded, require_made_for
from roughcontact.pipeline.progress import scene_progress
from roughcontact.pipeline.sources import for_case

SURFACE_VARIABLES = ["heights", "rms_slope", "alpha"]


def main(log):
    settings, cases, kind = snakemake.params.settings, snakemake.params.cases, snakemake.params.kind
    unit = snakemake.params.surface["unit"]  # a generator block and a reader's settings name the length unit
    if kind == "batch":  # even of one seed (the last of the seeds)
        solve_batch(log, cases, contact_case(settings, length_unit=unit, threads=snakemake.threads))
    elif kind == "ranks":
        solve_over_ranks(log, cases[0], contact_case(settings, length_unit=unit))
    else:
        solve_one(log, cases[0], contact_case(settings, length_unit=unit, threads=snakemake.threads))
    scene = scene_progress(Path(snakemake.output[0]).parents[1])  # results/{scene}
    if scene is not None:
        log.info(scene[1].text(scene[0]))


def labels(case):
    """The case's labels as contact_dataset names them (the wildcards' strings; H is hurst)."""
    return {"hurst" if key == "H" else key: value for key, value in case.items()}


def made_with(case):
    """What the case's surface must have been made with: its source's record (generator block, reader settings)."""
    return {for_case(case).record_key: snakemake.params.surface}


def solve_one(log, case, contact):
    """One surface in this process: a generated case (k_l, k_s, H, seed) or a measured scene's file."""
    path = snakemake.input[0]
    surf = read_dataset(path, stage="surface", variables=SURFACE_VARIABLES)
    require_made_for(surf, path, case, **made_with(case))
    heights, length = surface_heights(surf, path)
    rms_slope = float(surf.rms_slope.squeeze())
    check_case_loads(contact, rms_slope)  # a final load its effects cannot carry, named by its config field
    [result] = run_case(heights, contact, length=length, rms_slope=rms_slope, log=log,
                        name=Path(snakemake.output[0]).stem)
    ds = contact_dataset(result, rms_slope=rms_slope, alpha=float(surf.alpha.squeeze()), e_star=contact.settings.e_star,
                         **labels(case))
    write_dataset(ds, snakemake.output[0], stage="contact", scene=snakemake.wildcards.scene,
                  scene_parameters={**recorded(surf), **snakemake.params.settings})
    log.info("contact %s: A/A0 %.4g -> %.4g, %d iterations in %.2f s", snakemake.output[0],
             float(result.area_fraction[0]), float(result.area_fraction[-1]),
             int(result.iterations.sum()), float(np.sum(result.wall_time)))


def solve_over_ranks(log, case, contact):
    """One generated surface over MPI ranks. This process never holds the surface (34 GB at 65536²): it checks
    the file from its header and a sample of rows (surface_grid), and each rank reads and checks its own rows."""
    path = snakemake.input[0]
    with lazy_dataset(path, stage="surface", variables=SURFACE_VARIABLES) as surf:
        require_made_for(surf, path, case, **made_with(case))
        shape, length = surface_grid(surf, path)  # a NaN in rows it does not sample: the ranks name it
        rms_slope, alpha, recorded_by = float(surf.rms_slope.squeeze()), float(surf.alpha.squeeze()), recorded(surf)
    [result] = run_case(path, contact, length=length, rms_slope=rms_slope, shape=shape,
                        launcher=snakemake.resources.launcher, log=log, name=Path(snakemake.output[0]).stem)
    ds = contact_dataset(result, rms_slope=rms_slope, alpha=alpha, e_star=contact.settings.e_star,
                         **labels(case))
    write_dataset(ds, snakemake.output[0], stage="contact", scene=snakemake.wildcards.scene,
                  scene_parameters={**recorded_by, **snakemake.params.settings})
    log.info("contact over %d ranks %s: A/A0 %.4g -> %.4g, %d iterations in %.2f s", contact.ranks,
             snakemake.output[0], float(result.area_fraction[0]), float(result.area_fraction[-1]),
             int(result.iterations.sum()), float(result.wall_time.sum()))


def solve_batch(log, cases, contact):
    """The seeds of one (k_l, k_s, H) solved together; the file holds one group a case, named by its stem."""
    settings = snakemake.params.settings
    surfs, heights, stems = [], [], []
    for path, case in zip(snakemake.input, cases, strict=True):
        surf = read_dataset(path, stage="surface", variables=SURFACE_VARIABLES)
        require_made_for(surf, path, case, **made_with(case))
        h, length = surface_heights(surf, path)
        surfs.append(surf)
        heights.append(h)
        stems.append(Path(path).stem)
    slopes = [float(surf.rms_slope.squeeze()) for surf in surfs]
    results = run_case(np.stack(heights), contact, length=length, rms_slope=slopes, log=log, name=stems)
    e_star = contact.settings.e_star
    members = {
        stem: (contact_dataset(result, rms_slope=slope, alpha=float(surf.alpha.squeeze()), e_star=e_star,
                               k_l=case["k_l"], k_s=case["k_s"], hurst=case["H"], seed=int(case["seed"])),
               {**recorded(surf), **settings})
        for stem, case, result, surf, slope in zip(stems, cases, results, surfs, slopes, strict=True)
    }
    write_groups(members, snakemake.output[0], stage="contact_batch", member_stage="contact",
                 scene=snakemake.wildcards.scene,
                 scene_parameters={**settings, "seeds": [int(case["seed"]) for case in cases],
                                   "surface": snakemake.params.surface})
    for stem, result in zip(stems, results, strict=True):
        log.info("contact %s: A/A0 %.4g -> %.4g, %d iterations", stem, float(result.area_fraction[0]),
                 float(result.area_fraction[-1]), int(result.iterations.sum()))
    log.info("batch %s: %d cases, %d rounds in %.2f s", snakemake.output[0], len(cases),
             int(results[0].rounds.sum()), float(np.sum(results[0].wall_time)))


run_logged(snakemake.log[0], main)

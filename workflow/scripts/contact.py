"""Stage 3: solve the contact of one surface (generated or measured) over the scene's load steps; with
contact.solver.batch > 1, copy the case out of its batch's file (workflow/scripts/contact_batch.py solved it),
with contact.solver.ranks > 1 out of its MPI job's file (workflow/scripts/contact_mpi.py)."""
from pathlib import Path

import numpy as np

from roughcontact.case import run_case
from roughcontact.pipeline.case import check_case_loads, contact_case
from roughcontact.pipeline.datasets import contact_dataset, surface_heights
from roughcontact.pipeline.io import read_dataset, run_logged, write_dataset
from roughcontact.pipeline.params import recorded, require_made_for
from roughcontact.pipeline.progress import scene_progress
from roughcontact.pipeline.sources import for_case


def main(log):
    w, settings = snakemake.wildcards, snakemake.params.settings
    case = {key: getattr(w, key) for key in w.keys() if key != "scene"}  # k_l, k_s, H, seed; or topography
    if "batch" in snakemake.input.keys() or "mpi" in snakemake.input.keys():
        copy_solved(log, w, case, settings)
        return
    surf = read_dataset(snakemake.input[0], stage="surface", variables=["heights", "rms_slope", "alpha"])
    # a surface records what it was made with under its source's key (generator block, reader settings)
    require_made_for(surf, snakemake.input[0], case, **{for_case(case).record_key: snakemake.params.surface})
    heights, length = surface_heights(surf, snakemake.input[0])
    # both a generator block and a reader's settings name the study's length unit
    contact = contact_case(settings, length_unit=snakemake.params.surface["unit"], threads=snakemake.threads)
    rms_slope = float(surf.rms_slope.squeeze())
    check_case_loads(contact, rms_slope)  # a final load its effects cannot carry, named by its config field
    result = run_case(heights, contact, length=length, rms_slope=rms_slope, log=log,
                      name=Path(snakemake.output[0]).stem)
    ds = contact_dataset(result, rms_slope=rms_slope, alpha=float(surf.alpha.squeeze()), e_star=contact.settings.e_star,
                         **{"hurst" if key == "H" else key: value for key, value in case.items()})
    write_dataset(ds, snakemake.output[0], stage="contact", scene=w.scene,
                  scene_parameters={**recorded(surf), **settings})
    log.info("contact %s: A/A0 %.4g -> %.4g, %d iterations in %.2f s", snakemake.output[0],
             float(result.area_fraction[0]), float(result.area_fraction[-1]),
             int(result.iterations.sum()), float(np.sum(result.wall_time)))
    scene = scene_progress(Path(snakemake.output[0]).parents[1])  # results/{scene}
    if scene is not None:
        log.info(scene[1].text(scene[0]))


def copy_solved(log, w, case, settings):
    """The case solved by another job (its group of a batch's file, or an MPI job's file), checked to be this case
    made with these settings, as its own file."""
    batched = "batch" in snakemake.input.keys()
    path = snakemake.input.batch if batched else snakemake.input.mpi
    ds = read_dataset(path, stage="contact", group=Path(snakemake.output[0]).stem if batched else None).drop_encoding()
    require_made_for(ds, path, case, **settings)
    write_dataset(ds, snakemake.output[0], stage="contact", scene=w.scene, scene_parameters=recorded(ds))
    area = ds.area_fraction.values.ravel()
    log.info("contact %s: A/A0 %.4g -> %.4g, %d iterations (solved in %s)", snakemake.output[0], area[0], area[-1],
             int(ds.iterations.sum()), path)


run_logged(snakemake.log[0], main)

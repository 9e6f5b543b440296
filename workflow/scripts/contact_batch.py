"""Stage 3, batched (contact.solver.batch > 1): solve one batch's seeds together, one group per case in its file."""
from pathlib import Path

import numpy as np

from roughcontact.case import run_case
from roughcontact.pipeline.case import contact_case
from roughcontact.pipeline.cases import Case
from roughcontact.pipeline.datasets import contact_dataset, surface_heights
from roughcontact.pipeline.io import read_dataset, run_logged, write_groups
from roughcontact.pipeline.params import recorded, require_made_for
from roughcontact.pipeline.progress import scene_progress


def main(log):
    w, settings, seeds = snakemake.wildcards, snakemake.params.settings, snakemake.params.seeds
    cases = [Case(w.k_l, w.k_s, w.H, seed) for seed in seeds]
    surfs, heights = [], []
    for path, case in zip(snakemake.input, cases, strict=True):
        surf = read_dataset(path, stage="surface", variables=["heights", "rms_slope", "alpha"])
        require_made_for(surf, path, {"k_l": w.k_l, "k_s": w.k_s, "H": w.H, "seed": case.seed},
                         surface=snakemake.params.surface)
        h, length = surface_heights(surf, path)
        surfs.append(surf)
        heights.append(h)
    contact = contact_case(settings, length_unit=snakemake.params.surface["unit"], threads=snakemake.threads)
    e_star = contact.settings.e_star
    slopes = [float(surf.rms_slope.squeeze()) for surf in surfs]
    results = run_case(np.stack(heights), contact, length=length, rms_slope=slopes, log=log,
                       name=[case.stem for case in cases])
    members = {
        case.stem: (contact_dataset(result, rms_slope=slope, alpha=float(surf.alpha.squeeze()), e_star=e_star,
                                    k_l=w.k_l, k_s=w.k_s, hurst=w.H, seed=case.seed),
                    {**recorded(surf), **settings})
        for case, result, surf, slope in zip(cases, results, surfs, slopes, strict=True)
    }
    write_groups(members, snakemake.output[0], stage="contact_batch", member_stage="contact", scene=w.scene,
                 scene_parameters={**settings, "seeds": list(seeds), "surface": snakemake.params.surface})
    for case, result in zip(cases, results, strict=True):
        log.info("contact %s: A/A0 %.4g -> %.4g, %d iterations", case.stem, float(result.area_fraction[0]),
                 float(result.area_fraction[-1]), int(result.iterations.sum()))
    log.info("batch %s: %d cases, %d rounds in %.2f s", snakemake.output[0], len(cases),
             int(results[0].rounds.sum()), float(np.sum(results[0].wall_time)))
    scene = scene_progress(Path(snakemake.output[0]).parents[1])  # results/{scene}
    if scene is not None:
        log.info(scene[1].text(scene[0]))


run_logged(snakemake.log[0], main)

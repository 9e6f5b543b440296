"""Stage 1: generate one surface (a map, or a profile with surface.dimension: 1) and write it (thin wrapper over
roughcontact.surfaces.synthetic)."""
from roughcontact.pipeline.datasets import generated_heights, surface_dataset
from roughcontact.pipeline.io import run_logged, write_dataset


def main(log):
    w, surf = snakemake.wildcards, snakemake.params.surface
    norm = {k: surf[k] for k in ("rms_slope", "rms_height") if k in surf}
    h = generated_heights(surf, w.k_l, w.k_s, w.H, int(w.seed))
    ds = surface_dataset(h, k_l=w.k_l, k_s=w.k_s, hurst=w.H, seed=int(w.seed), length=surf["L"], normalisation=norm,
                         length_unit=surf["unit"])
    write_dataset(ds, snakemake.output[0], stage="surface", scene=w.scene, scene_parameters={"surface": surf})
    log.info("surface %s: rms slope %.6g, rms height %.6g, alpha %.4g", snakemake.output[0],
             float(ds.rms_slope.squeeze()), float(ds.rms_height.squeeze()), float(ds.alpha.squeeze()))


run_logged(snakemake.log[0], main)

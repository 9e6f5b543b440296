"""Stage 2 (measured): eps of one topography file's heights."""
from roughcontact.pipeline.datasets import representativity_dataset, surface_heights
from roughcontact.pipeline.io import read_dataset, run_logged, write_dataset
from roughcontact.pipeline.params import require_made_for
from roughcontact.statistics.representativity import gaussian_l2_error


def main(log):
    w, settings = snakemake.wildcards, snakemake.params.settings
    path = snakemake.input[0]
    surf = read_dataset(path, stage="surface", variables=["heights"])
    require_made_for(surf, path, {"topography": w.topography}, topography=snakemake.params.surface)
    heights, _ = surface_heights(surf, path)
    eps = gaussian_l2_error(heights, settings["n_bins"])
    ds = representativity_dataset(eps, heights, n_bins=settings["n_bins"], topography=w.topography,
                                  length_unit=surf.attrs["length_units"])
    write_dataset(ds, snakemake.output[0], stage="representativity", scene=w.scene,
                  scene_parameters={**settings, "topography": snakemake.params.surface})
    log.info("eps of %s: %.6g -> %s", w.topography, eps, snakemake.output[0])


run_logged(snakemake.log[0], main)

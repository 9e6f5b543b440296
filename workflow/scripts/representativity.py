"""Stage 2: L2 distance between a surface's height PDF and its Gaussian."""
from roughcontact.datasets import representativity_dataset, surface_heights
from roughcontact.io import read_dataset, run_logged, write_dataset
from roughcontact.params import recorded, require_made_for
from roughcontact.representativity import gaussian_l2_error


def main(log):
    w, settings = snakemake.wildcards, snakemake.params.settings
    surf = read_dataset(snakemake.input[0], stage="surface", variables=["heights"])
    require_made_for(surf, snakemake.input[0], {"k_l": w.k_l, "k_s": w.k_s, "H": w.H, "seed": w.seed},
                     surface=snakemake.params.surface)
    h, _ = surface_heights(surf, snakemake.input[0])
    eps = gaussian_l2_error(h, settings["n_bins"])
    ds = representativity_dataset(eps, h, n_bins=settings["n_bins"], k_l=w.k_l, k_s=w.k_s, hurst=w.H,
                                  seed=int(w.seed))
    write_dataset(ds, snakemake.output[0], stage="representativity", scene=w.scene,
                  scene_parameters={**recorded(surf), **settings})
    log.info("epsilon = %.6g for %s", eps, snakemake.input[0])


run_logged(snakemake.log[0], main)

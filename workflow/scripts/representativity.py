"""Stage 2: eps of every seed of one grid point, its surfaces made in memory."""
from roughcontact.datasets import representativity_batch
from roughcontact.io import run_logged, write_dataset


def main(log):
    w, settings = snakemake.wildcards, snakemake.params.settings
    ds = representativity_batch(settings["surface"], k_l=w.k_l, k_s=w.k_s, hurst=w.H, seeds=settings["seeds"],
                                n_bins=settings["n_bins"])
    write_dataset(ds, snakemake.output[0], stage="representativity", scene=w.scene, scene_parameters=settings)
    eps = ds.epsilon.values.ravel()
    log.info("eps over %d seeds: mean %.6g, min %.6g, max %.6g -> %s", eps.size, eps.mean(), eps.min(),
             eps.max(), snakemake.output[0])


run_logged(snakemake.log[0], main)

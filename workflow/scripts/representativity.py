"""Stage 2: eps of every k_s and seed of one (k_l, H), its surfaces made in memory."""
import time

from roughcontact.pipeline.datasets import representativity_batch
from roughcontact.pipeline.io import run_logged, write_dataset


def main(log):
    w, settings = snakemake.wildcards, snakemake.params.settings
    cpu, wall = time.process_time(), time.perf_counter()
    ds = representativity_batch(settings["surface"], k_l=w.k_l, k_s=settings["k_s"], hurst=w.H,
                                seeds=settings["seeds"], n_bins=settings["n_bins"])
    write_dataset(ds, snakemake.output[0], stage="representativity", scene=w.scene, scene_parameters=settings)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    eps = ds.epsilon.values.ravel()
    # benchmarks/bench_representativity.py reads this line: the job's work without its start-up
    log.info("computed %d surfaces in %.3f s CPU, %.3f s wall", eps.size, cpu, wall)
    log.info("eps over %d surfaces: mean %.6g, min %.6g, max %.6g -> %s", eps.size, eps.mean(), eps.min(),
             eps.max(), snakemake.output[0])


run_logged(snakemake.log[0], main)

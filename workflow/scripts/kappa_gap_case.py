"""Kappa gap: solve one surface of one variant and record every area definition per load step."""
import time

from roughcontact.pipeline.io import run_logged, write_dataset
from roughcontact.studies.kappa_gap.cases import case_surface, solve_case


def main(log):
    w, block = snakemake.wildcards, snakemake.params.settings
    s = block["setting"]
    h = case_surface(w.k_l, w.k_s, w.H, int(w.seed), int(s["N"]), block)
    t0 = time.perf_counter()
    ds = solve_case(h, s, length=block["surface"]["L"], thresholds=block["gap_thresholds"])
    seconds = time.perf_counter() - t0
    ds.attrs.update(variant=w.variant, k_l=w.k_l, k_s=w.k_s, H=w.H, seed=int(w.seed))
    write_dataset(ds, snakemake.output[0], stage="kappa_gap", scene=w.scene, scene_parameters=block)
    log.info("%s: %s N=%s, %d iterations, %.1f s, every step ended by its solver's rule %s", snakemake.output[0],
             s["method"], s["N"], int(ds.iterations.sum()), seconds, bool(ds.stopped.all()))


run_logged(snakemake.log[0], main)

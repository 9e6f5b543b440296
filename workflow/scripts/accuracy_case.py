"""Accuracy study: generate one surface at the setting's N and solve it at its tol and steps."""
from roughcontact.case import run_case
from roughcontact.pipeline.case import accuracy_case
from roughcontact.pipeline.datasets import contact_dataset
from roughcontact.pipeline.io import run_logged, write_dataset
from roughcontact.surfaces.synthetic import generate_surface, spectral_moments


def main(log):
    w, block = snakemake.wildcards, snakemake.params.settings
    s = block["setting"]
    n, length = int(s["N"]), block["surface"]["L"]
    h = generate_surface(n, float(w.k_l), float(w.k_s), float(w.H), int(w.seed),
                         rms_slope=block["surface"]["rms_slope"], length=length)
    stats = spectral_moments(h, length)
    [result] = run_case(h, accuracy_case(block, threads=snakemake.threads), length=length,
                        rms_slope=stats["rms_slope"])
    ds = contact_dataset(result, rms_slope=stats["rms_slope"], alpha=stats["alpha"], e_star=1.0,
                         k_l=w.k_l, k_s=w.k_s, hurst=w.H, seed=int(w.seed))
    ds.attrs.update(setting=w.variant, n=n, length=length)
    write_dataset(ds, snakemake.output[0], stage="contact", scene=snakemake.wildcards.scene,
                  scene_parameters=block)
    log.info("%s: %d iterations, %.2f s, converged %s", snakemake.output[0], int(result.iterations.sum()),
             float(result.wall_time.sum()), bool(result.converged.all()))


run_logged(snakemake.log[0], main)

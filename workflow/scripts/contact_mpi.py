"""Stage 3 over MPI ranks (contact.solver.ranks > 1): solve one case split over the job's MPI processes
(`mpiexec -n R` locally, `srun -n R` in a SLURM job: the rule's `mpi` resource); the case's contact job
copies the file (workflow/scripts/contact.py).

This process never holds the surface (34 GB at 65536²): it checks the file from its header and a sample of
rows (roughcontact.pipeline.datasets.surface_grid), and each rank reads and checks its own rows."""
from roughcontact.case import run_case_on_ranks
from roughcontact.pipeline.case import contact_case
from roughcontact.pipeline.datasets import contact_dataset, surface_grid
from roughcontact.pipeline.io import lazy_dataset, run_logged, write_dataset
from roughcontact.pipeline.params import recorded, require_made_for


def main(log):
    w, settings = snakemake.wildcards, snakemake.params.settings
    case = {key: getattr(w, key) for key in ("k_l", "k_s", "H", "seed")}
    path = snakemake.input[0]
    with lazy_dataset(path, stage="surface", variables=["heights", "rms_slope", "alpha"]) as surf:
        require_made_for(surf, path, case, surface=snakemake.params.surface)
        shape, length = surface_grid(surf, path)  # a NaN in rows it does not sample: the ranks name it
        rms_slope, alpha, made_with = float(surf.rms_slope.squeeze()), float(surf.alpha.squeeze()), recorded(surf)
    contact = contact_case(settings, length_unit=snakemake.params.surface["unit"])
    result = run_case_on_ranks(path, contact, length=length, rms_slope=rms_slope, shape=shape,
                               launcher=snakemake.resources.mpi, log=log, name=f"kl{w.k_l}_ks{w.k_s}_H{w.H}_s{w.seed}")
    ds = contact_dataset(result, rms_slope=rms_slope, alpha=alpha, e_star=contact.settings.e_star,
                         k_l=w.k_l, k_s=w.k_s, hurst=w.H, seed=w.seed)
    write_dataset(ds, snakemake.output[0], stage="contact", scene=w.scene,
                  scene_parameters={**made_with, **settings})
    log.info("contact over %d ranks %s: A/A0 %.4g -> %.4g, %d iterations in %.2f s", contact.ranks,
             snakemake.output[0], float(result.area_fraction[0]), float(result.area_fraction[-1]),
             int(result.iterations.sum()), float(result.wall_time.sum()))


run_logged(snakemake.log[0], main)

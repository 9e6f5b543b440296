"""Aggregate: join every contact case of a scene into one dataset with seed statistics."""
from roughcontact import aggregate
from roughcontact.config import cases
from roughcontact.io import read_dataset, run_logged, write_dataset

REQUIRED = ["pressure", "area_fraction", "mean_contact_pressure", "kappa", "converged", "rms_slope"]


def main(log):
    block = snakemake.params.block
    paths = list(snakemake.input)
    datasets = [read_dataset(p, stage="contact", variables=REQUIRED) for p in paths]
    expected = [(float(c.k_l), float(c.k_s), float(c.H), c.seed) for c in cases(block)]
    ds = aggregate.combine_cases(datasets, paths, expected=expected)
    ds = aggregate.add_derived(ds)
    ds = ds.merge(aggregate.seed_statistics(ds))
    bad = ds["n_unconverged"]
    if int(bad.sum()):
        log.warning("%d case(s) have unconverged load steps (see n_unconverged); fits exclude them "
                    "unless the scene's fit.include_unconverged is true", int((bad > 0).sum()))
    write_dataset(ds, snakemake.output[0], stage="aggregate", scene=snakemake.params.scene, scene_parameters=block)
    log.info("aggregated %d contact cases into %s", len(paths), snakemake.output[0])


run_logged(snakemake.log[0], main)

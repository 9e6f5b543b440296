"""Aggregate: join every representativity case of a scene, with mean and error over seeds."""
from roughcontact import aggregate
from roughcontact.config import cases
from roughcontact.io import read_dataset, run_logged, write_dataset


def main(log):
    block = snakemake.params.block
    paths = list(snakemake.input)
    datasets = [read_dataset(p, stage="representativity", variables=["epsilon"]) for p in paths]
    expected = [(float(c.k_l), float(c.k_s), float(c.H), c.seed) for c in cases(block)]
    ds = aggregate.combine_cases(datasets, paths, expected=expected, kind="representativity")
    ds = ds.merge(aggregate.representativity_statistics(ds))
    write_dataset(ds, snakemake.output[0], stage="aggregate", scene=snakemake.params.scene, scene_parameters=block)
    log.info("aggregated %d representativity cases into %s", len(paths), snakemake.output[0])


run_logged(snakemake.log[0], main)

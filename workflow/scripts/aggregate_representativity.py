"""Aggregate: join every representativity case of a scene, with mean and error over seeds."""
from roughcontact.analysis import aggregate
from roughcontact.pipeline import provenance
from roughcontact.pipeline.datasets import split_cases
from roughcontact.pipeline.io import read_dataset, run_logged, write_dataset


def main(log):
    cases = snakemake.params.cases
    if cases and isinstance(cases[0], str):  # measured surfaces: one file per topography
        paths = list(snakemake.input)
        datasets = [read_dataset(p, stage="representativity", variables=["epsilon"]) for p in paths]
        ds = aggregate.combine_topographies(datasets, paths, expected=cases, kind="representativity")
    else:
        datasets, paths = [], []
        for path in snakemake.input:
            batch = read_dataset(path, stage="representativity", variables=["epsilon"])
            for one in split_cases(batch):
                datasets.append(one)
                paths.append(f"{path} (k_s {one.k_s.values[0]:g}, seed {int(one.seed.values[0])})")
        expected = [(float(kl), float(ks), float(h), int(s)) for kl, ks, h, s in cases]
        ds = aggregate.combine_cases(datasets, paths, expected=expected, kind="representativity")
        ds = ds.merge(aggregate.representativity_statistics(ds))
    ds, common, varying = provenance.attach_settings(ds, datasets)
    if varying:
        log.warning("cases were computed with different settings: %s; each case's value is in the "
                    "variables setting_*", ", ".join(varying))
        ds.attrs["varying_parameters"] = ", ".join(varying)
    write_dataset(ds, snakemake.output[0], stage="aggregate", scene=snakemake.wildcards.scene,
                  scene_parameters=common)
    log.info("aggregated %d representativity cases from %d files into %s", len(datasets),
             len(snakemake.input), snakemake.output[0])


run_logged(snakemake.log[0], main)

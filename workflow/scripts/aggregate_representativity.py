"""Aggregate: join every representativity case of a scene, with mean and error over seeds."""
from roughcontact.pipeline import provenance
from roughcontact.pipeline.io import read_dataset, run_logged, write_dataset
from roughcontact.pipeline.sources import for_dims


def main(log):
    # the surface source whose case dimensions the files have splits them into cases (a generated
    # scene's files are (k_l, H) batches) and stacks them, with its statistics
    datasets, paths, source = [], [], None
    for path in snakemake.input:
        batch = read_dataset(path, stage="representativity", variables=["epsilon"])
        source = source or for_dims(batch.dims)
        for one, label in source.unbatch(path, batch):
            datasets.append(one)
            paths.append(label)
    ds = source.aggregate(datasets, paths, snakemake.params.cases, kind="representativity")
    ds, common, varying = provenance.attach_settings(ds, datasets)
    if varying:
        # a patch file's own settings (its path, unit, size) differ by design: no warning for them
        log.log(30 if source.unexpected_settings(varying) else 20, "cases were computed with different "
                "settings: %s; each case's value is in the variables setting_*", ", ".join(varying))
        ds.attrs["varying_parameters"] = ", ".join(varying)
    write_dataset(ds, snakemake.output[0], stage="aggregate", scene=snakemake.wildcards.scene,
                  scene_parameters=common)
    log.info("aggregated %d representativity cases from %d files into %s", len(datasets),
             len(snakemake.input), snakemake.output[0])


run_logged(snakemake.log[0], main)

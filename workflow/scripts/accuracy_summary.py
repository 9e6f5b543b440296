"""Accuracy study: errors against the reference and the solver work of every setting."""
from collections import defaultdict
from pathlib import Path

from roughcontact.analysis import aggregate
from roughcontact.core.files import atomic_output, write_text_atomic
from roughcontact.pipeline.io import read_dataset, run_logged, write_dataset
from roughcontact.studies import accuracy


def main(log):
    block = snakemake.params.settings
    settings = accuracy.variants(block)
    groups = defaultdict(lambda: ([], []))
    for nc in snakemake.input.cases:
        ds = read_dataset(nc, stage="contact",
                          variables=["area_fraction", "contact_perimeter", "pressure", "rms_slope", "iterations"])
        datasets, names = groups[Path(nc).parent.name]
        datasets.append(ds)
        names.append(nc)
    results = {}
    for label, (datasets, names) in groups.items():
        agg = aggregate.add_derived(aggregate.combine_cases(datasets, names))
        unconverged = int((~agg["converged"].astype(bool)).sum())
        if unconverged:
            log.warning("setting %s: %d unconverged load steps", label, unconverged)
        results[label] = agg
    summary = accuracy.summarize(results, settings, length=block["surface"]["L"], kappa_at=block["kappa_at"],
                                 seed_axis=block["seed_axis"], n_boot=block["n_boot"])
    write_dataset(summary, snakemake.output.nc, stage="accuracy", scene=snakemake.wildcards.scene,
                  scene_parameters=block)
    per_variant = summary.drop_vars([v for v in summary.variables if summary[v].dims != ("variant",)])
    with atomic_output(snakemake.output.csv) as tmp:
        per_variant.to_dataframe().to_csv(tmp)
    table = accuracy.markdown_table(summary)
    write_text_atomic(snakemake.output.md, table)
    log.info("accuracy summary:\n%s\nperimeter c fitted: %.4g (default %.4g)", table,
             summary.attrs["perimeter_c_fit"], summary.attrs["perimeter_c"])


run_logged(snakemake.log[0], main)

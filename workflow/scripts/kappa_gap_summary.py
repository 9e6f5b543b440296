"""Kappa gap: pair the variants surface by surface and write the table."""
from collections import defaultdict
from pathlib import Path

from roughcontact.core.files import write_text_atomic
from roughcontact.pipeline.io import read_dataset, run_logged, write_dataset
from roughcontact.studies import kappa_gap


def main(log):
    block = snakemake.params.settings
    cases = defaultdict(list)
    for path in snakemake.input.cases:
        cases[Path(path).parent.name].append(read_dataset(path, stage="kappa_gap"))
    data = kappa_gap.collect(cases, block)
    write_dataset(data, snakemake.output.nc, stage="kappa_gap", scene=snakemake.wildcards.scene,
                  scene_parameters=block)
    text = kappa_gap.markdown(kappa_gap.summarise(data))
    write_text_atomic(snakemake.output.md, text)
    log.info("kappa gap:\n%s", text)


run_logged(snakemake.log[0], main)

"""Render one registered figure (roughcontact.figures.registry) to PNG and PDF (deterministic bytes)."""
from roughcontact.figures.registry import FIGURES
from roughcontact.figures.style import save_figure
from roughcontact.pipeline.io import run_logged


def main(log):
    name = snakemake.wildcards.figure
    fig = FIGURES[name].render(dict(snakemake.input.items()))
    save_figure(fig, snakemake.output.png)
    log.info("figure %s written", name)


run_logged(snakemake.log[0], main)

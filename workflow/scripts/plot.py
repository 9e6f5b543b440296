"""Render one registered figure (roughcontact.figures.registry) to PNG and PDF (deterministic bytes), and its
report caption: the lead in workflow/report/ and the reference lines the figure drew (figures.captions)."""
from pathlib import Path

from roughcontact.core.files import write_text_atomic
from roughcontact.figures.captions import caption
from roughcontact.figures.registry import FIGURES
from roughcontact.figures.style import save_figure
from roughcontact.pipeline.io import run_logged


def main(log):
    name = snakemake.wildcards.figure
    fig = FIGURES[name].render(dict(snakemake.input.items()))
    lead = (Path(snakemake.scriptdir).parent / "report" / FIGURES[name].caption).read_text(encoding="utf-8")
    text = caption(lead, fig)
    save_figure(fig, snakemake.output.png)
    write_text_atomic(snakemake.output.caption, text)
    log.info("figure %s written", name)


run_logged(snakemake.log[0], main)

"""Render one registered figure (roughcontact.figures.registry) to PNG and PDF (deterministic bytes), the record of
what it drew (figures.record) and its report caption built from that record: the lead in workflow/report/, then
what this rendering drew (figures.captions)."""
from pathlib import Path

from roughcontact.core.files import write_text_atomic
from roughcontact.figures.captions import caption
from roughcontact.figures.record import figure_record, record_json
from roughcontact.figures.registry import FIGURES
from roughcontact.figures.style import save_figure
from roughcontact.pipeline.io import run_logged


def main(log):
    name = snakemake.wildcards.figure
    fig = FIGURES[name].render(dict(snakemake.input.items()))
    lead = (Path(snakemake.scriptdir).parent / "report" / FIGURES[name].caption).read_text(encoding="utf-8")
    record = figure_record(name, fig)
    save_figure(fig, snakemake.output.png)
    write_text_atomic(snakemake.output.caption, caption(lead, record))
    write_text_atomic(snakemake.output.record, record_json(record))
    log.info("figure %s written", name)


run_logged(snakemake.log[0], main)

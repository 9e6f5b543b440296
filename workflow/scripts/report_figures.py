"""The report's landing-page figures: each figure of the scene embedded, with its caption (studies.report)."""
from pathlib import Path

from roughcontact.core.files import write_text_atomic
from roughcontact.pipeline.io import run_logged
from roughcontact.studies import report


def main(log):
    figures = [(Path(png).stem, Path(png).read_bytes(), Path(caption).read_text(encoding="utf-8"))
               for png, caption in zip(snakemake.input.png, snakemake.input.caption, strict=True)]
    write_text_atomic(snakemake.output[0], report.figures_rst(figures))
    log.info("%d figure(s) for the landing page written to %s", len(figures), snakemake.output[0])


run_logged(snakemake.log[0], main)

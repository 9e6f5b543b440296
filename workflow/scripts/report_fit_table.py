"""cel.csv as an HTML table the report shows (studies.report.csv_html): a browser downloads a CSV instead."""
from pathlib import Path

from roughcontact.core.files import write_text_atomic
from roughcontact.pipeline.io import run_logged
from roughcontact.studies import report


def main(log):
    text = Path(snakemake.input[0]).read_text(encoding="utf-8")
    write_text_atomic(snakemake.output[0], report.csv_html(text, f"fit/cel.csv of scene {snakemake.wildcards.scene}"))
    log.info("%s written", snakemake.output[0])


run_logged(snakemake.log[0], main)

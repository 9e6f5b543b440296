"""The report's landing-page fragment: scene parameters, version, git commit, CEL fit table."""
from pathlib import Path

from roughcontact import __version__, report
from roughcontact.io import run_logged, write_text_atomic


def main(log):
    fit = snakemake.input.fit
    fit_csv = Path(fit[0]).read_text(encoding="utf-8") if fit else None
    # The checkout that holds this workflow; "unknown" when it is not a git work tree.
    commit = report.git_commit(Path(snakemake.scriptdir))
    text = report.summary_rst(snakemake.wildcards.scene, snakemake.params.parameters, version=__version__,
                              commit=commit, fit_csv=fit_csv)
    write_text_atomic(snakemake.output[0], text)
    log.info("report summary written to %s (version %s, commit %s)", snakemake.output[0], __version__, commit)


run_logged(snakemake.log[0], main)

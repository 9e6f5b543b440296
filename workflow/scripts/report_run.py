"""The run's record for the report: code, library versions, host, date and total CPU time (studies.run_record)."""
import datetime
from pathlib import Path

from roughcontact import __version__
from roughcontact.core.files import write_text_atomic
from roughcontact.pipeline.io import run_logged
from roughcontact.studies import report, run_record


def main(log):
    results = Path(snakemake.output[0]).parent.parent
    # The checkout that holds this workflow; "unknown" when it is not a git work tree.
    commit = report.git_commit(Path(snakemake.scriptdir))
    cpu = run_record.cpu_text(*run_record.total_cpu(results))
    text = run_record.run_record_rst(version=__version__, commit=commit, versions=run_record.library_versions(),
                                     host=run_record.host_text(), when=datetime.datetime.now(datetime.UTC),
                                     cpu=cpu)
    write_text_atomic(snakemake.output[0], text)
    log.info("run record written to %s (version %s, commit %s, %s)", snakemake.output[0], __version__, commit, cpu)


run_logged(snakemake.log[0], main)

"""The report's landing-page fragments: the result line (or pull-off table), and the fit, tables and parameters."""
from pathlib import Path

from roughcontact.core.files import write_text_atomic
from roughcontact.pipeline.case import contact_effects
from roughcontact.pipeline.io import read_dataset, run_logged
from roughcontact.studies import report, report_intro, report_tables


def topographies():
    """A measured scene's table of its files (report_tables.topographies_table), or None for a generated one."""
    surfaces = snakemake.input.surfaces
    if not surfaces:
        return None
    contact = snakemake.input.contact
    agg = read_dataset(contact[0], stage="aggregate", variables=["pressure"]) if contact else None
    rows = []
    for path in surfaces:
        name = Path(path).stem
        surface = read_dataset(path, stage="surface", variables=["rms_slope"])
        rows.append(report_tables.topography_row(name, surface, None if agg is None else agg.sel(topography=name)))
    return report_tables.topographies_table(rows)


def pull_off():
    """The pull-off table (report_tables.pull_off_table) where an effect brings it (adhesion), or None."""
    contact = snakemake.params.parameters.get("contact")
    if contact is None or not any("pull_off" in e.tables for e in contact_effects(contact)):
        return None
    agg = read_dataset(snakemake.input.contact[0], stage="aggregate", variables=["pull_off_pressure"])
    return report_tables.pull_off_table(agg)


def unfitted():
    """The contact the scene computes where its effects keep no contact evolution law (e.g. "adhesive contact"), for
    the result line of a scene with neither a fit nor a table of its own; None otherwise."""
    contact = snakemake.params.parameters.get("contact")
    names = [] if contact is None else [e.contact_name for e in contact_effects(contact)
                                        if not e.keeps_elastic_law and e.contact_name]
    return " and ".join(names) or None


def profiles():
    """Whether the scene's cases are profiles (1-D surfaces): generated with surface.dimension 1, or line scans (the
    contact aggregate of a patch scene, which this job reads, has surface_dimension 1)."""
    if snakemake.params.parameters.get("contact", {}).get("surface", {}).get("dimension") == 1:
        return True
    contact = snakemake.input.contact
    if not contact:
        return False
    agg = read_dataset(contact[0], stage="aggregate", variables=["pressure"])
    return int(agg.attrs.get("surface_dimension", 2)) == 1


def main(log):
    fit = snakemake.input.fit
    fit_csv = Path(fit[0]).read_text(encoding="utf-8") if fit else None
    lines = profiles()
    write_text_atomic(snakemake.output.result, report.result_rst(fit_csv, pull_off=pull_off(), profiles=lines,
                                                                  unfitted=unfitted()))
    text = report.summary_rst(snakemake.wildcards.scene, snakemake.params.parameters, fit_csv=fit_csv,
                              topographies=topographies(), profiles=lines)
    write_text_atomic(snakemake.output.summary, text)
    write_text_atomic(snakemake.output.intro, report_intro.intro_rst(snakemake.wildcards.scene, snakemake.params.intro))
    log.info("report fragments written: %s, %s", snakemake.output.result, snakemake.output.summary)


run_logged(snakemake.log[0], main)

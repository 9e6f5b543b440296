# The report's landing page: reStructuredText fragments that workflow/report/workflow.rst includes (not
# report items themselves: the landing page shows them). intro.rst (the stages the scene runs, the contact
# evolution law only where it is fitted: roughcontact.studies.report_intro) opens the page; result.rst (the fitted CEL constants against the
# paper's, or an adhesive scene's pull-off) above the figures, figures.rst (each figure embedded, with its
# caption), summary.rst (fit table, the scene's tables, its parameters) below them; rendered by roughcontact.studies.report. Their params are the
# scene's study blocks without the description (roughcontact.pipeline.params.summary), so a description
# edit plans nothing. run.rst, the run's record (code, versions, host, date, CPU time:
# roughcontact.studies.run_record), is written after every other output of the scene.

from roughcontact.studies.report_intro import intro_facts


localrules:
    report_summary,
    report_fit_table,
    report_figures,
    report_run,


rule report_summary:
    input:
        fit=lambda w: (
            [f"results/{w.scene}/fit/cel.csv"]
            if "contact" in scene_of(w.scene) and follows_elastic_law(scene_of(w.scene)["contact"])
            else []
        ),
        # a patch source's table of its files (measured, array, ...): each surface, and the loads they received
        surfaces=lambda w: [f"results/{w.scene}/surfaces/{name}.nc" for name in patch_names(w.scene)],
        # a patch source's table, and the tables an effect brings (an adhesive scene's pull-off), read the
        # contact aggregate
        contact=lambda w: (
            [f"results/{w.scene}/aggregate/contact.nc"]
            if "contact" in scene_of(w.scene)
            and (patch_names(w.scene) or any(e.tables for e in contact_effects(scene_of(w.scene)["contact"])))
            else []
        ),
    output:
        result="results/{scene}/report/result.rst",
        summary="results/{scene}/report/summary.rst",
        intro="results/{scene}/report/intro.rst",
    log:
        "results/{scene}/logs/report_summary.log",
    benchmark:
        "results/{scene}/benchmarks/report_summary.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    params:
        parameters=lambda w: params.summary(SCENES[w.scene]),
        intro=lambda w: intro_facts(SCENES[w.scene]),
    script:
        "../scripts/report_summary.py"


rule report_fit_table:
    input:
        "results/{scene}/fit/cel.csv",
    output:
        report(
            "results/{scene}/fit/cel.html",
            caption="../report/fit_table.rst",
            category="Fit",
        ),
    log:
        "results/{scene}/logs/report_fit_table.log",
    benchmark:
        "results/{scene}/benchmarks/report_fit_table.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/report_fit_table.py"


rule report_figures:
    input:
        unpack(report_figure_inputs),
    output:
        "results/{scene}/report/figures.rst",
    log:
        "results/{scene}/logs/report_figures.log",
    benchmark:
        "results/{scene}/benchmarks/report_figures.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/report_figures.py"


# run.rst is a report item as well (category Run): every scene's report then has one, from which the landing page
# finds the scene's fragments (workflow/report/workflow.rst), a scene that draws no figure included.
rule report_run:
    input:
        run_record_inputs,
    output:
        report(
            "results/{scene}/report/run.rst",
            caption="../report/run_record.rst",
            category="Run",
        ),
    log:
        "results/{scene}/logs/report_run.log",
    benchmark:
        "results/{scene}/benchmarks/report_run.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/report_run.py"

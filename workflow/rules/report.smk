# The report's landing page: a reStructuredText fragment (scene parameters, version, git commit,
# CEL fit table) that workflow/report/workflow.rst includes. Rendered by roughcontact.studies.report.
# Its params are the scene's study blocks without the description (roughcontact.pipeline.params.summary),
# so a description edit plans nothing; the commit is read when the job runs.


localrules:
    report_summary,


rule report_summary:
    input:
        fit=lambda w: (
            [f"results/{w.scene}/fit/cel.csv"]
            if "contact" in scene_of(w.scene) and not is_adhesive(scene_of(w.scene)["contact"])
            else []
        ),
        # a patch source's table of its files (measured, array, ...): each surface, and the loads they received
        surfaces=lambda w: [f"results/{w.scene}/surfaces/{name}.nc" for name in patch_names(w.scene)],
        # a patch source's table, and an adhesive scene's pull-off table, read the contact aggregate
        contact=lambda w: (
            [f"results/{w.scene}/aggregate/contact.nc"]
            if "contact" in scene_of(w.scene) and (patch_names(w.scene) or is_adhesive(scene_of(w.scene)["contact"]))
            else []
        ),
    output:
        report(
            "results/{scene}/report/summary.rst",
            caption="../report/summary.rst",
            category="Summary",
        ),
    log:
        "results/{scene}/logs/report_summary.log",
    benchmark:
        "results/{scene}/benchmarks/report_summary.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    params:
        parameters=lambda w: params.summary(SCENES[w.scene]),
    script:
        "../scripts/report_summary.py"

# Stage 4: one dataset over the grid, then the contact-evolution-law fit.
# The aggregates take every case's settings from the case's own file; their only
# parameter is the list of cases, each checked against the file that claims it.


localrules:
    aggregate_representativity,
    aggregate_contact,
    fit_cel,


rule aggregate_representativity:
    input:
        lambda w: batch_files(w.scene, "representativity", "representativity"),
    output:
        "results/{scene}/aggregate/representativity.nc",
    log:
        "results/{scene}/logs/aggregate_representativity.log",
    benchmark:
        "results/{scene}/benchmarks/aggregate_representativity.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    params:
        cases=case_list("representativity"),
    script:
        "../scripts/aggregate_representativity.py"


rule aggregate_contact:
    input:
        lambda w: contact_files(w.scene),
    output:
        "results/{scene}/aggregate/contact.nc",
    log:
        "results/{scene}/logs/aggregate_contact.log",
    benchmark:
        "results/{scene}/benchmarks/aggregate_contact.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    params:
        cases=case_list("contact"),
        # each case's file and its group there (a batch's file holds one group a case)
        members=lambda w: contact_members_of(w.scene),
    script:
        "../scripts/aggregate_contact.py"


rule fit_cel:
    input:
        "results/{scene}/aggregate/contact.nc",
    output:
        nc="results/{scene}/fit/cel.nc",
        csv=report("results/{scene}/fit/cel.csv", caption="../report/fit.rst", category="Fit"),
    log:
        "results/{scene}/logs/fit_cel.log",
    benchmark:
        "results/{scene}/benchmarks/fit_cel.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    params:
        fit=lambda w: params.fit(SCENES[w.scene]) if study_block(w.scene, "contact") else None,
    script:
        "../scripts/fit_cel.py"

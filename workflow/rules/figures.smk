# Figures: one rule per figure, PNG and PDF, byte-identical across reruns.


localrules:
    fig_representativity,
    fig_surface_examples,
    fig_area_load,
    fig_kappa,
    fig_dpbar,


rule fig_representativity:
    input:
        rep="results/{scene}/aggregate/representativity.nc",
    output:
        png=report("results/{scene}/figures/representativity.png", caption="../report/representativity.rst", category="Representativity"),
        pdf="results/{scene}/figures/representativity.pdf",
    params:
        figure="representativity",
    log:
        "results/{scene}/logs/fig_representativity.log",
    benchmark:
        "results/{scene}/benchmarks/fig_representativity.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/plot.py"


rule fig_surface_examples:
    input:
        surfaces=example_surfaces,
    output:
        png=report("results/{scene}/figures/surface_examples.png", caption="../report/surface_examples.rst", category="Representativity"),
        pdf="results/{scene}/figures/surface_examples.pdf",
    params:
        figure="surface_examples",
    log:
        "results/{scene}/logs/fig_surface_examples.log",
    benchmark:
        "results/{scene}/benchmarks/fig_surface_examples.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/plot.py"


rule fig_area_load:
    input:
        agg="results/{scene}/aggregate/contact.nc",
        fit="results/{scene}/fit/cel.nc",
    output:
        png=report("results/{scene}/figures/area_load.png", caption="../report/area_load.rst", category="Contact"),
        pdf="results/{scene}/figures/area_load.pdf",
    params:
        figure="area_load",
    log:
        "results/{scene}/logs/fig_area_load.log",
    benchmark:
        "results/{scene}/benchmarks/fig_area_load.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/plot.py"


rule fig_kappa:
    input:
        agg="results/{scene}/aggregate/contact.nc",
        fit="results/{scene}/fit/cel.nc",
    output:
        png=report("results/{scene}/figures/kappa.png", caption="../report/kappa.rst", category="Contact"),
        pdf="results/{scene}/figures/kappa.pdf",
    params:
        figure="kappa",
    log:
        "results/{scene}/logs/fig_kappa.log",
    benchmark:
        "results/{scene}/benchmarks/fig_kappa.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/plot.py"


rule fig_dpbar:
    input:
        agg="results/{scene}/aggregate/contact.nc",
        fit="results/{scene}/fit/cel.nc",
    output:
        png=report("results/{scene}/figures/dpbar.png", caption="../report/dpbar.rst", category="Contact"),
        pdf="results/{scene}/figures/dpbar.pdf",
    params:
        figure="dpbar",
    log:
        "results/{scene}/logs/fig_dpbar.log",
    benchmark:
        "results/{scene}/benchmarks/fig_dpbar.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/plot.py"

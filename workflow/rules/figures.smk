# Figures: one rule for every figure of roughcontact.figures.registry.FIGURES, PNG and PDF,
# byte-identical across reruns. A scene gets the figures its blocks ask for.


localrules:
    figure,


rule figure:
    input:
        unpack(figure_inputs),
    output:
        png=report(
            "results/{scene}/figures/{figure}.png",
            caption="../report/figure.rst",
            category=lambda w: FIGURES[w.figure].category,
        ),
        pdf="results/{scene}/figures/{figure}.pdf",
    log:
        "results/{scene}/logs/figure_{figure}.log",
    benchmark:
        "results/{scene}/benchmarks/figure_{figure}.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    params:
        # Derived from the output, so Snakemake does not rerun a figure for a new caption.
        caption=lambda w, output: figure_caption(w.figure),
    script:
        "../scripts/plot.py"

# Figures: one rule for every figure of roughcontact.figures.registry.FIGURES, PNG and PDF,
# byte-identical across reruns, and the figure's report caption (figures.captions: its lead in
# workflow/report/ and the reference lines this rendering drew), which workflow/report/figure.rst shows.
# A scene gets the figures its blocks ask for.


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
        # the vector version, attached to the report beside the PNG the landing page shows
        pdf=report(
            "results/{scene}/figures/{figure}.pdf",
            category=lambda w: FIGURES[w.figure].category,
            subcategory="vector PDF",
        ),
        caption="results/{scene}/figures/{figure}.caption.rst",
    log:
        "results/{scene}/logs/figure_{figure}.log",
    benchmark:
        "results/{scene}/benchmarks/figure_{figure}.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/plot.py"

# Figures: one rule for every figure of roughcontact.figures.registry.FIGURES, PNG and PDF,
# byte-identical across reruns, the record of what the rendering drew (figures.record: its data series,
# reference lines, fits with their route, window) and the figure's report caption built from that record
# (figures.captions: its lead in workflow/report/, then what was drawn), which workflow/report/figure.rst
# shows. A scene gets the figures its blocks ask for.


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
        record="results/{scene}/figures/{figure}.record.json",
    log:
        "results/{scene}/logs/figure_{figure}.log",
    benchmark:
        "results/{scene}/benchmarks/figure_{figure}.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/plot.py"

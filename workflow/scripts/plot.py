"""Render one of the paper's figures to PNG and PDF (deterministic bytes)."""
from roughcontact import plots
from roughcontact.io import read_dataset, run_logged


def main(log):
    name = snakemake.params.figure
    if name == "representativity":
        rep = read_dataset(snakemake.input.rep, stage="aggregate", variables=["epsilon"])
        fig = plots.fig_representativity(rep)
    elif name == "accuracy":
        fig = plots.fig_accuracy(read_dataset(snakemake.input.summary, stage="accuracy", variables=["err_kappa"]))
    elif name == "surface_examples":
        surfaces = [read_dataset(p, stage="surface", variables=["heights"]) for p in snakemake.input.surfaces]
        fig = plots.fig_surface_examples([
            (s.heights.values.squeeze(), f"$k_l$ = {float(s.k_l[0]):g}, $k_s$ = {float(s.k_s[0]):g}")
            for s in surfaces
        ])
    else:
        agg = read_dataset(snakemake.input.agg, stage="aggregate", variables=["area_fraction"])
        cel = read_dataset(snakemake.input.fit, stage="fit")
        draw = {"area_load": plots.fig_area_load, "kappa": plots.fig_kappa, "dpbar": plots.fig_dpbar}[name]
        fig = draw(agg, agg, cel)
    plots.save_figure(fig, snakemake.output.png)
    log.info("figure %s written", name)


run_logged(snakemake.log[0], main)

"""Fit the contact evolution law (kappa, mu, beta) with bootstrap uncertainty."""
from roughcontact import fit
from roughcontact.io import read_dataset, run_logged, write_dataset


def main(log):
    cfg = snakemake.params.fit
    agg = read_dataset(snakemake.input[0], stage="aggregate", variables=["area_fraction", "pressure"])
    if not cfg["include_unconverged"] and "n_unconverged" in agg:
        excluded = int((agg["n_unconverged"] > 0).sum())
        if excluded:
            log.warning("excluding %d case(s) with unconverged steps from the fit", excluded)
        agg = agg.where(agg["n_unconverged"] == 0)
    result = fit.fit_cel(agg, window=tuple(cfg["window"]), n_boot=cfg["n_boot"], rng_seed=cfg["rng_seed"])
    write_dataset(result, snakemake.output.nc, stage="fit", scene=snakemake.params.scene, scene_parameters=cfg)
    with open(snakemake.output.csv, "w") as fh:
        fh.write(fit.to_csv_table(result))
    log.info("CEL fit written to %s", snakemake.output.nc)


run_logged(snakemake.log[0], main)

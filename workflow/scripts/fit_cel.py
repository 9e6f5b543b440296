"""Fit the contact evolution law (kappa, mu, beta) with bootstrap uncertainty."""
from roughcontact import fit
from roughcontact.io import read_dataset, run_logged, write_dataset, write_text_atomic


def main(log):
    cfg = snakemake.params.fit
    agg = read_dataset(snakemake.input[0], stage="aggregate", variables=["area_fraction", "pressure"])
    if not cfg["include_unconverged"]:
        agg, excluded = fit.exclude_unconverged(agg)
        if excluded:
            log.warning("excluding %d case(s) with unconverged steps from the fit: (k_l, k_s, H, seed) = %s",
                        len(excluded), "; ".join(str(c) for c in excluded))
    # One group that cannot be fitted (too few points in the window, a joint fit that does not
    # converge on a non-representative case) must not sink the others: it is reported as NaN.
    result = fit.fit_cel(agg, window=tuple(cfg["window"]), n_boot=cfg["n_boot"], rng_seed=cfg["rng_seed"],
                         on_insufficient="nan")
    kappa = result["value"].sel(constant="kappa").to_series()
    for group in kappa[kappa.isna()].index:
        log.warning("no CEL fit for (k_l, k_s, H, estimator) = %s", group)
    loose = result["constrained"].where(result["value"].notnull(), 1).to_series()
    for group in loose[loose == 0].index:
        log.warning("not constrained by the data (bootstrap interval wider than the value), flagged in cel.csv: "
                    "(k_l, k_s, H, estimator, constant) = %s", group)
    # NaN is a legitimate value here: it marks a group without a fit.
    for name in result.data_vars:
        if result[name].dtype.kind == "f":
            result[name].attrs["allow_nan"] = 1
    write_dataset(result, snakemake.output.nc, stage="fit", scene=snakemake.wildcards.scene, scene_parameters=cfg)
    write_text_atomic(snakemake.output.csv, fit.to_csv_table(result))
    log.info("CEL fit written to %s", snakemake.output.nc)


run_logged(snakemake.log[0], main)

"""Fit the contact evolution law (kappa, mu, beta) with bootstrap uncertainty.

The surface source whose case dimensions the aggregate has says which fit
(roughcontact.pipeline.sources): a generated scene's aggregate (dims k_l, k_s, H, seed, step) is fitted
per (k_l, k_s, H) and pooled over H by fit.fit_cel ("grid"); a patch source's (measured, array, ...:
dims topography, step) by fit.fit_topographies ("topographies"), all its patches pooled as one
surface type.
"""
from roughcontact.analysis import fit
from roughcontact.analysis.aggregate import TOPOGRAPHY_DIM
from roughcontact.core.files import write_text_atomic
from roughcontact.pipeline.io import read_dataset, run_logged, write_dataset
from roughcontact.pipeline.sources import for_dims


def main(log):
    cfg = snakemake.params.fit
    agg = read_dataset(snakemake.input[0], stage="aggregate", variables=["area_fraction", "pressure"])
    measured = for_dims(agg.dims).fit == "topographies"
    cases = "topographies" if measured else "(k_l, k_s, H, seed)"
    if not cfg["include_unconverged"]:
        agg, excluded = fit.exclude_unconverged(agg)
        if excluded:
            log.warning("excluding %d case(s) with unconverged steps from the fit: %s = %s",
                        len(excluded), cases, "; ".join(str(c) for c in excluded))
    unresolved = fit.unresolved_in_window(agg, tuple(cfg["window"]))
    if unresolved:
        log.warning("leaving %d load step(s) in the fit's window out of the fit: their contact is unresolved (largest "
                    "patch under 4 nodes, contact_resolved in the aggregate): A/A0 there is the grid's",
                    unresolved)
    # One group that cannot be fitted (too few points in the window, a joint fit that does not
    # converge on a non-representative case) must not sink the others: it is reported as NaN.
    fitter = fit.fit_topographies if measured else fit.fit_cel
    # cases loaded differently (load.target_area: each ends at its own p0; measured files loaded relative
    # to e_star on surfaces of different slopes) have no common schedule to average step by step: every
    # (case, step) point enters the paper route, each case on its own schedule (config/README.md)
    result = fitter(agg, window=tuple(cfg["window"]), n_boot=cfg["n_boot"], rng_seed=cfg["rng_seed"],
                    on_insufficient="nan", paper_average="auto")
    if result.attrs["paper_average"] == "none":
        log.info("the cases' load schedules p0/(E* h') differ (load.target_area, or loads relative to E* on "
                 "surfaces of different slopes): the paper route fits every (case, step) point on each case's "
                 "own schedule instead of the mean curve over %s", "topographies" if measured else "seeds")
    if measured:
        _log_topographies(log, result)
    else:
        _log_groups(log, result)
    # NaN is a legitimate value here: it marks a group without a fit.
    for name in result.data_vars:
        if result[name].dtype.kind == "f":
            result[name].attrs["allow_nan"] = 1
    write_dataset(result, snakemake.output.nc, stage="fit", scene=snakemake.wildcards.scene, scene_parameters=cfg)
    write_text_atomic(snakemake.output.csv, fit.to_csv_table(result))
    log.info("CEL fit written to %s", snakemake.output.nc)


def _log_groups(log, result):
    kappa = result["value"].sel(constant="kappa").to_series()
    for group in kappa[kappa.isna()].index:
        log.warning("no CEL fit for (k_l, k_s, H, estimator) = %s", group)
    loose = result["constrained"].where(result["value"].notnull(), 1).to_series()
    for group in loose[loose == 0].index:
        log.warning("not constrained by the data (%s), flagged in cel.csv: (k_l, k_s, H, estimator, constant) = %s",
                    fit.UNCONSTRAINED_RULE, group)


def _log_topographies(log, result):
    n = int(result["n_topographies"])
    names = [str(t) for t, used in zip(result[TOPOGRAPHY_DIM].values, result["in_fit"].values, strict=True) if used]
    log.info("topographies pooled in the fit (%d): %s", n, ", ".join(names) or "none")
    if n == 1:
        log.warning("a single topography: no bootstrap interval (one surface says nothing about the scatter "
                    "between surfaces); cel.csv flags its constants as not constrained")
    for estimator in result["estimator"].values:
        value = result["value"].sel(estimator=estimator)
        if value.isnull().any():
            if n == 0:  # else the fit has logged why (roughcontact.analysis.fit.bootstrap)
                log.warning("no CEL fit (%s): no topography to fit", estimator)
        elif n > 1:
            loose = [str(c) for c in result["constant"].values
                     if not int(result["constrained"].sel(estimator=estimator, constant=c))]
            if loose:
                log.warning("not constrained by the data (%s), flagged in cel.csv: estimator %s, constant(s) %s",
                            fit.UNCONSTRAINED_RULE, estimator, ", ".join(loose))


run_logged(snakemake.log[0], main)

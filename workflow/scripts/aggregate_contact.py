"""Aggregate: join every contact case of a scene into one dataset with seed statistics."""
from roughcontact.pipeline import provenance
from roughcontact.pipeline.io import read_dataset, run_logged, write_dataset
from roughcontact.pipeline.sources import for_dims
from roughcontact.statistics.patches import MIN_PATCH_NODES

UNLOADING_DIMS = ["unload_step"]
REQUIRED = ["pressure", "area_fraction", "mean_contact_pressure", "kappa", "converged", "rms_slope"]


def main(log):
    members = snakemake.params.members  # [file, group] a case, in the order of the cases
    paths = [path if group is None else f"{path} (group {group})" for path, group in members]
    # an adhesive case's unloading branch has as many steps as that case needed: it stays in the case's
    # file (the hysteresis figure reads it there); its pull-off and status are per-case scalars
    datasets = [read_dataset(path, stage="contact", variables=REQUIRED, group=group).drop_dims(UNLOADING_DIMS,
                                                                                             errors="ignore")
                for path, group in members]
    # the surface source whose case dimensions the files have stacks them (with its statistics)
    source = for_dims(datasets[0].dims)
    ds = source.aggregate(datasets, paths, snakemake.params.cases)
    ds, common, varying = provenance.attach_settings(ds, datasets)
    if varying:
        # a patch file's own settings (its path, unit, size) differ by design: no warning for them
        log.log(30 if source.unexpected_settings(varying) else 20, "cases were solved with different settings: %s; "
                "each case's value is in the variables %s", ", ".join(varying),
                ", ".join(sorted(v for v in ds if v.startswith("setting_"))))
        ds.attrs["varying_parameters"] = ", ".join(varying)
    bad = ds["n_unconverged"]
    if int(bad.sum()):
        log.warning("%d case(s) have unconverged load steps (see n_unconverged); fits exclude them "
                    "unless the scene's fit.include_unconverged is true", int((bad > 0).sum()))
    if "n_unresolved" in ds and int(ds["n_unresolved"].sum()):
        log.warning("%d load step(s) of %d case(s) have a contact the grid does not resolve (largest patch under %d "
                    "nodes: see contact_resolved and largest_patch_nodes); the figures mark them and the CEL fit, "
                    "where the scene has one, leaves them out", int(ds["n_unresolved"].sum()),
                    int((ds["n_unresolved"] > 0).sum()), MIN_PATCH_NODES)
    write_dataset(ds, snakemake.output[0], stage="aggregate", scene=snakemake.wildcards.scene,
                  scene_parameters=common)
    log.info("aggregated %d contact cases into %s", len(paths), snakemake.output[0])


run_logged(snakemake.log[0], main)

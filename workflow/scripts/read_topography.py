"""Stage 1 (a patch source: measured, array, ...): read one named case's file and write it as a surface
with its statistics. The source's ``read`` builder reads it (roughcontact.pipeline.sources); its reader
settings name the source (``source``), a measured file's settings by omission (files made before the
registry record them so)."""
import json

from roughcontact.pipeline.datasets import measured_surface_dataset
from roughcontact.pipeline.io import run_logged, write_dataset
from roughcontact.pipeline.sources import SOURCES
from roughcontact.surfaces.topography import WARN_UNDEFINED


def main(log):
    w, s = snakemake.wildcards, snakemake.params.settings
    measured = SOURCES[s.get("source", "measured")].read(s)
    if measured.info.get("undefined_fraction", 0.0) > WARN_UNDEFINED:
        log.warning("%s: %.1f%% of the points are undefined (not measured) and were filled (%s); the map's "
                    "statistics and contact there are the fill's", w.topography,
                    100 * measured.info["undefined_fraction"], s["undefined"])
    ds = measured_surface_dataset(measured, name=w.topography)
    write_dataset(ds, snakemake.output[0], stage="surface", scene=w.scene, scene_parameters={"topography": s})
    log.info("topography %s from %s: %s", w.topography, s["path"], json.dumps(measured.info, sort_keys=True))
    grid = " x ".join(str(ds.sizes[d]) for d in ("x", "y") if d in ds.sizes)  # a line scan has x alone
    log.info("surface %s: %s points, %s %s, rms height %.6g %s, rms slope %.6g, alpha %.4g", snakemake.output[0],
             grid, " x ".join(f"{side:g}" for side in measured.lengths), measured.unit,
             float(ds.rms_height.squeeze()), measured.unit, float(ds.rms_slope.squeeze()), float(ds.alpha.squeeze()))


run_logged(snakemake.log[0], main)

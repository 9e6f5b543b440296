"""The pipeline's plumbing: config and scenes, job parameters, datasets and NetCDF I/O, provenance,
progress, run cost."""

# Stage 1: surfaces by FFT filtering of white noise, one NetCDF per case.
# Two rules share one script: the representativity and contact studies may normalise
# surfaces differently (rms height vs rms slope), so they live in separate folders.


def _surface_params(study):
    return dict(
        scene=lambda w: w.scene,
        study=study,
        block=lambda w: check_case(w, study),
    )


rule surface_rep:
    output:
        (
            "results/{scene}/surfaces_rep/" + CASE + ".nc"
            if SCENES[ACTIVE_SCENE].get("representativity", {}).get("keep_surfaces", True)
            else temp("results/{scene}/surfaces_rep/" + CASE + ".nc")
        ),
    params:
        **_surface_params("representativity"),
    log:
        "results/{scene}/logs/surface_rep/" + CASE + ".log",
    benchmark:
        "results/{scene}/benchmarks/surface_rep/" + CASE + ".tsv"
    resources:
        mem_mb=lambda w: surface_mem_mb(SCENES[w.scene]["representativity"]["surface"]["N"]),
        runtime=5,
    script:
        "../scripts/generate_surface.py"


rule surface:
    output:
        (
            "results/{scene}/surfaces/" + CASE + ".nc"
            if SCENES[ACTIVE_SCENE].get("contact", {}).get("keep_surfaces", True)
            else temp("results/{scene}/surfaces/" + CASE + ".nc")
        ),
    params:
        **_surface_params("contact"),
    log:
        "results/{scene}/logs/surface/" + CASE + ".log",
    benchmark:
        "results/{scene}/benchmarks/surface/" + CASE + ".tsv"
    resources:
        mem_mb=lambda w: surface_mem_mb(SCENES[w.scene]["contact"]["surface"]["N"]),
        runtime=5,
    script:
        "../scripts/generate_surface.py"

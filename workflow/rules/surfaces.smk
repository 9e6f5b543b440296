# Stage 1: surfaces by FFT filtering of white noise, one NetCDF per case.
# Two rules share one script: the representativity and contact studies may normalise
# surfaces differently (rms height vs rms slope), so they live in separate folders.
# params carry exactly what a surface depends on (roughcontact.pipeline.params.surface). A generated
# surface reads no file: its input function only checks the case against the scene's grid.


rule surface_rep:
    input:
        case_input("representativity"),
    output:
        maybe_temp(case_path("surfaces_rep"), "representativity"),
    log:
        case_path("logs/surface_rep", "log"),
    benchmark:
        case_path("benchmarks/surface_rep", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    resources:
        mem_mb=lambda w: surface_mem_mb(map_side(SCENES[w.scene]["representativity"]["surface"])),
        runtime=lambda w: surface_runtime_min(map_side(SCENES[w.scene]["representativity"]["surface"])),
    params:
        surface=case_params("representativity", params.surface),
    script:
        "../scripts/generate_surface.py"


rule surface:
    input:
        case_input("contact"),
    output:
        maybe_temp(case_path("surfaces"), "contact"),
    log:
        case_path("logs/surface", "log"),
    benchmark:
        case_path("benchmarks/surface", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    resources:
        mem_mb=lambda w: surface_mem_mb(map_side(SCENES[w.scene]["contact"]["surface"])),
        runtime=lambda w: surface_runtime_min(map_side(SCENES[w.scene]["contact"]["surface"])),
    params:
        surface=case_params("contact", params.surface),
    script:
        "../scripts/generate_surface.py"


# Measured surfaces: one topography file read by SurfaceTopography (roughcontact.surfaces.topography),
# converted to the scene's length unit, with its statistics. The file is the job's input, so an
# edited file is read again; params carry the reader settings of that file only.
rule topography:
    input:
        topography_file,
    output:
        topography_path("surfaces"),
    log:
        topography_path("logs/surface", "log"),
    benchmark:
        topography_path("benchmarks/surface", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    resources:
        mem_mb=measured_mem_mb,
        runtime=10,
    params:
        settings=topography_params(),
    script:
        "../scripts/read_topography.py"

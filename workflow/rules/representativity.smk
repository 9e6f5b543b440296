# Stage 2: L2 distance between each surface's height PDF and its Gaussian.


rule representativity:
    input:
        case_path("surfaces_rep"),
    output:
        case_path("representativity"),
    log:
        case_path("logs/representativity", "log"),
    benchmark:
        case_path("benchmarks/representativity", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    resources:
        mem_mb=lambda w: surface_mem_mb(SCENES[w.scene]["representativity"]["surface"]["N"]),
        runtime=lambda w: surface_runtime_min(SCENES[w.scene]["representativity"]["surface"]["N"]),
    params:
        settings=case_params("representativity", params.representativity),
        surface=case_params("representativity", params.surface),
    script:
        "../scripts/representativity.py"

# Stage 2: L2 distance between each surface's height PDF and its Gaussian.


rule representativity:
    input:
        case_path("surfaces_rep"),
    output:
        case_path("representativity"),
    params:
        settings=case_params("representativity", params.representativity),
        surface=case_params("representativity", params.surface),
    log:
        case_path("logs/representativity", "log"),
    benchmark:
        case_path("benchmarks/representativity", "tsv")
    resources:
        mem_mb=lambda w: surface_mem_mb(SCENES[w.scene]["representativity"]["surface"]["N"]),
        runtime=lambda w: surface_runtime_min(SCENES[w.scene]["representativity"]["surface"]["N"]),
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/representativity.py"

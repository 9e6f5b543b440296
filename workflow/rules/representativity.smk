# Stage 2: L2 distance between each surface's height PDF and its Gaussian. One job per
# grid point (k_l, k_s, H) computes every seed, its surfaces made in memory: at N=1024 a
# surface and its eps take ~0.3 s, less than a job's start-up. Each seed stays
# addressable in the output (coordinate `seed`).


rule representativity:
    output:
        point_path("representativity"),
    log:
        point_path("logs/representativity", "log"),
    benchmark:
        point_path("benchmarks/representativity", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    resources:
        mem_mb=lambda w: surface_mem_mb(SCENES[w.scene]["representativity"]["surface"]["N"]),
        runtime=lambda w: batch_runtime_min(SCENES[w.scene]["representativity"]),
    params:
        settings=point_params("representativity", params.representativity),
    script:
        "../scripts/representativity.py"


# Measured surfaces: eps of one topography file's heights.
rule representativity_topography:
    input:
        topography_path("surfaces"),
    output:
        topography_path("representativity"),
    log:
        topography_path("logs/representativity", "log"),
    benchmark:
        topography_path("benchmarks/representativity", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    resources:
        mem_mb=measured_mem_mb,
        runtime=10,
    params:
        settings=topography_params("representativity", params.representativity),
        surface=topography_params(),
    script:
        "../scripts/representativity_topography.py"

# Stage 2: L2 distance between each surface's height PDF and its Gaussian. One job per
# (k_l, H) computes every k_s and seed, its surfaces made in memory: at N=1024 a surface
# and its eps take ~0.1 s of CPU against ~1.1 s of a job's start-up, so the paper's
# 6 k_s x 30 seeds a job keep the start-up near 5 % (benchmarks/bench_representativity.py).
# Each case stays addressable in the output (coordinates `k_s`, `seed`).


rule representativity:
    input:
        batch_input("representativity"),
    output:
        batch_path("representativity"),
    log:
        batch_path("logs/representativity", "log"),
    benchmark:
        batch_path("benchmarks/representativity", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    resources:
        mem_mb=lambda w: surface_mem_mb(map_side(SCENES[w.scene]["representativity"]["surface"])),
        runtime=lambda w: batch_runtime_min(SCENES[w.scene]["representativity"]),
    params:
        settings=batch_params("representativity", params.representativity),
    script:
        "../scripts/representativity.py"


# Measured surfaces: eps of one topography file's heights.
rule representativity_topography:
    input:
        topography_input("surfaces", "representativity"),
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

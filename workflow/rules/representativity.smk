# Stage 2: L2 distance between each surface's height PDF and its Gaussian.


rule representativity:
    input:
        "results/{scene}/surfaces_rep/" + CASE + ".nc",
    output:
        "results/{scene}/representativity/" + CASE + ".nc",
    params:
        scene=lambda w: w.scene,
        block=lambda w: check_case(w, "representativity"),
    log:
        "results/{scene}/logs/representativity/" + CASE + ".log",
    benchmark:
        "results/{scene}/benchmarks/representativity/" + CASE + ".tsv"
    resources:
        mem_mb=lambda w: surface_mem_mb(SCENES[w.scene]["representativity"]["surface"]["N"]),
        runtime=5,
    script:
        "../scripts/representativity.py"

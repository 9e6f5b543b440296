# Stage 2: L2 distance between each surface's height PDF and its Gaussian.


rule representativity:
    input:
        "results/{scene}/surfaces_rep/kl{k_l}_ks{k_s}_H{H}_s{seed}.nc",
    output:
        "results/{scene}/representativity/kl{k_l}_ks{k_s}_H{H}_s{seed}.nc",
    params:
        scene=lambda w: w.scene,
        block=lambda w: check_case(w, "representativity"),
    log:
        "results/{scene}/logs/representativity/kl{k_l}_ks{k_s}_H{H}_s{seed}.log",
    benchmark:
        "results/{scene}/benchmarks/representativity/kl{k_l}_ks{k_s}_H{H}_s{seed}.tsv"
    resources:
        mem_mb=lambda w: surface_mem_mb(SCENES[w.scene]["representativity"]["surface"]["N"]),
        runtime=lambda w: surface_runtime_min(SCENES[w.scene]["representativity"]["surface"]["N"]),
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/representativity.py"

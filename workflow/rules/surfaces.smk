# Stage 1: surfaces by FFT filtering of white noise, one NetCDF per case.
# Two rules share one script: the representativity and contact studies may normalise
# surfaces differently (rms height vs rms slope), so they live in separate folders.


rule surface_rep:
    output:
        maybe_temp("results/{scene}/surfaces_rep/kl{k_l}_ks{k_s}_H{H}_s{seed}.nc", "representativity"),
    params:
        scene=lambda w: w.scene,
        block=lambda w: check_case(w, "representativity"),
    log:
        "results/{scene}/logs/surface_rep/kl{k_l}_ks{k_s}_H{H}_s{seed}.log",
    benchmark:
        "results/{scene}/benchmarks/surface_rep/kl{k_l}_ks{k_s}_H{H}_s{seed}.tsv"
    resources:
        mem_mb=lambda w: surface_mem_mb(SCENES[w.scene]["representativity"]["surface"]["N"]),
        runtime=lambda w: surface_runtime_min(SCENES[w.scene]["representativity"]["surface"]["N"]),
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/generate_surface.py"


rule surface:
    output:
        maybe_temp("results/{scene}/surfaces/kl{k_l}_ks{k_s}_H{H}_s{seed}.nc", "contact"),
    params:
        scene=lambda w: w.scene,
        block=lambda w: check_case(w, "contact"),
    log:
        "results/{scene}/logs/surface/kl{k_l}_ks{k_s}_H{H}_s{seed}.log",
    benchmark:
        "results/{scene}/benchmarks/surface/kl{k_l}_ks{k_s}_H{H}_s{seed}.tsv"
    resources:
        mem_mb=lambda w: surface_mem_mb(SCENES[w.scene]["contact"]["surface"]["N"]),
        runtime=lambda w: surface_runtime_min(SCENES[w.scene]["contact"]["surface"]["N"]),
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/generate_surface.py"

# Stage 3: frictionless normal contact, loaded in steps, one NetCDF per case.


rule contact:
    input:
        "results/{scene}/surfaces/kl{k_l}_ks{k_s}_H{H}_s{seed}.nc",
    output:
        "results/{scene}/contact/kl{k_l}_ks{k_s}_H{H}_s{seed}.nc",
    params:
        scene=lambda w: w.scene,
        block=lambda w: check_case(w, "contact"),
        pressures=lambda w: load_steps(check_case(w, "contact")),
    threads: 1
    log:
        "results/{scene}/logs/contact/kl{k_l}_ks{k_s}_H{H}_s{seed}.log",
    benchmark:
        "results/{scene}/benchmarks/contact/kl{k_l}_ks{k_s}_H{H}_s{seed}.tsv"
    resources:
        mem_mb=lambda w: contact_mem_mb(SCENES[w.scene]["contact"]["surface"]["N"]),
        runtime=lambda w: contact_runtime_min(
            SCENES[w.scene]["contact"]["surface"]["N"], SCENES[w.scene]["contact"]["load"]["n_steps"]
        ),
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/contact.py"

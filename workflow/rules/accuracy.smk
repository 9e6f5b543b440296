# The accuracy study: one numerical setting varied at a time around the most accurate one.


rule accuracy_case:
    output:
        "results/{scene}/accuracy/{variant}/kl{k_l}_ks{k_s}_H{H}_s{seed}.nc",
    params:
        scene=lambda w: w.scene,
        block=lambda w: study_block(w.scene, "accuracy"),
        setting=lambda w: accuracy_setting(w),
    threads: 1
    log:
        "results/{scene}/logs/accuracy/{variant}/kl{k_l}_ks{k_s}_H{H}_s{seed}.log",
    benchmark:
        "results/{scene}/benchmarks/accuracy/{variant}/kl{k_l}_ks{k_s}_H{H}_s{seed}.tsv"
    resources:
        mem_mb=lambda w: contact_mem_mb(int(accuracy_setting(w)["N"])),
        runtime=lambda w: contact_runtime_min(int(accuracy_setting(w)["N"]), int(accuracy_setting(w)["n_steps"])),
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/accuracy_case.py"


rule accuracy_summary:
    input:
        cases=lambda w: accuracy_files(w.scene, "results/{scene}/accuracy/{label}/{stem}.nc"),
        benchmarks=lambda w: accuracy_files(w.scene, "results/{scene}/benchmarks/accuracy/{label}/{stem}.tsv"),
    output:
        nc="results/{scene}/accuracy/summary.nc",
        csv="results/{scene}/accuracy/summary.csv",
        md=report("results/{scene}/accuracy/summary.md", caption="../report/accuracy.rst", category="Accuracy"),
    params:
        scene=lambda w: w.scene,
        block=lambda w: study_block(w.scene, "accuracy"),
    log:
        "results/{scene}/logs/accuracy_summary.log",
    benchmark:
        "results/{scene}/benchmarks/accuracy_summary.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/accuracy_summary.py"


rule fig_accuracy:
    input:
        summary="results/{scene}/accuracy/summary.nc",
    output:
        png=report("results/{scene}/figures/accuracy.png", caption="../report/accuracy.rst", category="Accuracy"),
        pdf="results/{scene}/figures/accuracy.pdf",
    params:
        figure="accuracy",
    log:
        "results/{scene}/logs/fig_accuracy.log",
    benchmark:
        "results/{scene}/benchmarks/fig_accuracy.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/plot.py"

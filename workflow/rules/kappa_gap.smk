# The kappa gap: what moves kappa at the representative point, one candidate at a time.


rule kappa_gap_case:
    input:
        kappa_gap_input,
    output:
        case_path("kappa_gap/{variant}"),
    log:
        case_path("logs/kappa_gap/{variant}", "log"),
    benchmark:
        case_path("benchmarks/kappa_gap/{variant}", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    threads: 1
    resources:
        mem_mb=lambda w: contact_mem_mb(int(kappa_gap_setting(w)["N"])),
        runtime=lambda w: 4 * contact_runtime_min(int(kappa_gap_setting(w)["N"]), kappa_gap_setting(w)["n_steps"]),
    params:
        settings=lambda w: params.kappa_gap_case(study_block(w.scene, "kappa_gap"), w.variant),
    script:
        "../scripts/kappa_gap_case.py"


rule kappa_gap_summary:
    input:
        cases=lambda w: kappa_gap_files(w.scene, "kappa_gap"),
    output:
        nc="results/{scene}/kappa_gap/kappa-gap.nc",
        md=report(
            "results/{scene}/kappa_gap/kappa-gap.md",
            caption="../report/kappa_gap.rst",
            category="Accuracy",
        ),
    log:
        "results/{scene}/logs/kappa_gap_summary.log",
    benchmark:
        "results/{scene}/benchmarks/kappa_gap_summary.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    params:
        settings=study_params("kappa_gap", params.kappa_gap_summary),
    script:
        "../scripts/kappa_gap_summary.py"

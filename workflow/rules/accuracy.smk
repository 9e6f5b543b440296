# The accuracy study: one numerical setting varied at a time around the most accurate one.


rule accuracy_case:
    input:
        accuracy_input,
    output:
        case_path("accuracy/{variant}"),
    log:
        case_path("logs/accuracy/{variant}", "log"),
    benchmark:
        case_path("benchmarks/accuracy/{variant}", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    threads: 1
    resources:
        mem_mb=lambda w: contact_mem_mb(int(accuracy_setting(w)["N"])),
        runtime=lambda w: contact_runtime_min(int(accuracy_setting(w)["N"]), int(accuracy_setting(w)["n_steps"])),
    params:
        settings=lambda w: params.accuracy_case(study_block(w.scene, "accuracy"), accuracy_setting(w)),
    script:
        "../scripts/accuracy_case.py"


rule accuracy_summary:
    input:
        cases=lambda w: accuracy_files(w.scene, "results/{scene}/accuracy/{label}/{stem}.nc"),
    output:
        nc="results/{scene}/accuracy/summary.nc",
        csv="results/{scene}/accuracy/summary.csv",
        md=report(
            "results/{scene}/accuracy/summary.md",
            caption="../report/accuracy.rst",
            category="Accuracy",
        ),
    log:
        "results/{scene}/logs/accuracy_summary.log",
    benchmark:
        "results/{scene}/benchmarks/accuracy_summary.tsv"
    conda:
        "../../envs/roughcontact.yaml"
    params:
        settings=study_params("accuracy", params.accuracy_summary),
    script:
        "../scripts/accuracy_summary.py"

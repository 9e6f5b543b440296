# Stage 3: frictionless normal contact, loaded in steps, one NetCDF per case.
# params carry exactly the settings a solve depends on (roughcontact.params.contact).


rule contact:
    input:
        case_path("surfaces"),
    output:
        case_path("contact"),
    params:
        settings=case_params("contact", params.contact),
        surface=case_params("contact", params.surface),
    threads: 1
    log:
        case_path("logs/contact", "log"),
    benchmark:
        case_path("benchmarks/contact", "tsv")
    resources:
        mem_mb=lambda w: contact_mem_mb(SCENES[w.scene]["contact"]["surface"]["N"]),
        runtime=lambda w: contact_runtime_min(
            SCENES[w.scene]["contact"]["surface"]["N"],
            SCENES[w.scene]["contact"]["load"]["n_steps"],
        ),
    conda:
        "../../envs/roughcontact.yaml"
    script:
        "../scripts/contact.py"

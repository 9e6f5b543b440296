# Stage 3: frictionless normal contact, loaded in steps, one NetCDF per case.
# params carry exactly the settings a solve depends on (roughcontact.params.contact).


rule contact:
    input:
        case_path("surfaces"),
    output:
        case_path("contact"),
    log:
        case_path("logs/contact", "log"),
    benchmark:
        case_path("benchmarks/contact", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    threads: 1
    resources:
        mem_mb=lambda w: contact_mem_mb(SCENES[w.scene]["contact"]["surface"]["N"]),
        runtime=lambda w: contact_runtime_min(
            SCENES[w.scene]["contact"]["surface"]["N"],
            SCENES[w.scene]["contact"]["load"]["n_steps"],
        ),
    params:
        settings=case_params("contact", params.contact),
        surface=case_params("contact", params.surface),
    script:
        "../scripts/contact.py"

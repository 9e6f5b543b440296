# Stage 3: frictionless normal contact, loaded in steps, one NetCDF per case.
# params carry exactly the settings a solve depends on (roughcontact.pipeline.params.contact).


rule contact:
    input:
        case_input("contact", "surfaces"),
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


# Measured surfaces: the same load steps on one topography file (free boundary by default).
rule contact_topography:
    input:
        topography_input("surfaces", "contact"),
    output:
        topography_path("contact"),
    log:
        topography_path("logs/contact", "log"),
    benchmark:
        topography_path("benchmarks/contact", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    threads: 1
    resources:
        mem_mb=measured_mem_mb,
        runtime=60,
    params:
        settings=topography_params("contact", params.contact),
        surface=topography_params(),
    script:
        "../scripts/contact.py"

# Stage 3: frictionless normal contact, loaded in steps, one NetCDF per case.
# params carry exactly the settings a solve depends on (roughcontact.pipeline.params.contact).
# With contact.solver.batch: B (> 1) the seeds of each (k_l, k_s, H) are solved B at a time by
# contact_batch (seeds 0..B-1, B..2B-1, ...: roughcontact.pipeline.cases.contact_batches), and each
# case's job copies its case out of its batch's file (roughcontact.pipeline.targets.Targets.contact_input).


rule contact_batch:
    input:
        contact_batch_input,
    output:
        contact_batch_path("contact_batch"),
    log:
        contact_batch_path("logs/contact_batch", "log"),
    benchmark:
        contact_batch_path("benchmarks/contact_batch", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    threads: 1
    resources:
        mem_mb=batch_job_mem_mb,
        runtime=batch_job_runtime_min,
    params:
        settings=contact_batch_params(params.contact),
        surface=contact_batch_params(params.surface),
        seeds=contact_batch_seeds,
    script:
        "../scripts/contact_batch.py"


rule contact:
    input:
        unpack(contact_input),
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
        mem_mb=contact_job_mem_mb,
        runtime=contact_job_runtime_min,
    params:
        settings=case_params("contact", params.contact),
        surface=case_params("contact", params.surface),
    script:
        "../scripts/contact.py"


# One case over MPI ranks (contact.solver.ranks > 1): an MPI job, `mpi` resource `mpiexec` locally (the
# SLURM profile sets `srun`), `tasks` the ranks; the case's contact job copies its file.
rule contact_mpi:
    input:
        contact_mpi_input,
    output:
        case_path("contact_mpi"),
    log:
        case_path("logs/contact_mpi", "log"),
    benchmark:
        case_path("benchmarks/contact_mpi", "tsv")
    conda:
        "../../envs/roughcontact.yaml"
    # locally the ranks' cores (the SLURM profile sets 1 CPU per task)
    threads: mpi_job_tasks
    resources:
        mem_mb=mpi_job_mem_mb,
        runtime=mpi_job_runtime_min,
        tasks=mpi_job_tasks,
        mpi="mpiexec",
    params:
        settings=contact_mpi_params(params.contact),
        surface=contact_mpi_params(params.surface),
    script:
        "../scripts/contact_mpi.py"


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

# Stage 3: frictionless normal contact, loaded in steps. One rule solves each group of cases and writes its file
# once (roughcontact.pipeline.contact_jobs): one case ({group} = kl{k_l}_ks{k_s}_H{H}_s{seed}, or a measured
# scene's file name), one case over contact.solver.ranks MPI processes (an MPI job: `mpi` and `tasks` the
# ranks; `launcher` mpiexec locally, srun under profiles/slurm), or with contact.solver.batch: B the seeds
# bB..bB+B-1 of one (k_l, k_s, H) ({group} = kl{k_l}_ks{k_s}_H{H}_b{b}: one NetCDF group a case).
# params carry exactly the settings a solve depends on (roughcontact.pipeline.params.contact).


rule contact:
    input:
        contact_input,
    output:
        contact_path("contact"),
    log:
        contact_path("logs/contact", "log"),
    benchmark:
        contact_path("benchmarks/contact", "tsv")
    # profiles/slurm packs these jobs into SLURM jobs of several (group-components); a case over ranks stays alone
    group:
        contact_bundle
    conda:
        "../../envs/roughcontact.yaml"
    # locally a case over ranks takes its ranks' cores (profiles/slurm sets 1 CPU per task)
    threads: contact_threads
    # a case over ranks: an MPI job (mpi: 1) of `tasks` ranks, started by `launcher` (srun under profiles/slurm),
    # its memory also per CPU (SLURM's --mem is per node: ranks over several nodes would ask each for all of it);
    # a job in one process has neither mpi nor tasks (the SLURM executor would make it an MPI job) nor memory per CPU
    resources:
        mem_mb=contact_job_mem_mb,
        mem_mb_per_cpu=contact_job_mem_mb_per_cpu,
        runtime=contact_job_runtime_min,
        tasks=contact_tasks,
        mpi=contact_mpi,
        launcher="mpiexec",
    params:
        settings=contact_params(params.contact),
        surface=contact_surface_params(params.surface),
        cases=contact_cases,
        kind=contact_kind,
    script:
        "../scripts/contact.py"

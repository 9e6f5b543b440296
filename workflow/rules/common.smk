# Shared set-up: the config validated once (roughcontact.pipeline.targets.Targets), the scenes and their
# surface sources, and the functions the rules call with a job's wildcards, each checking the requested
# file's wildcards against its scene (a mistyped target fails at once, naming the wildcard, its value and
# the scene's allowed values). Everything here is glue: the logic and its tests live in the package.
from pathlib import Path

from roughcontact.core.cli import one_line
from roughcontact.figures.registry import FIGURES
from roughcontact.pipeline import params
from roughcontact.pipeline.case import contact_effects, follows_elastic_law
from roughcontact.pipeline.scenes import plan_summary
from roughcontact.pipeline.progress import write_plan
from roughcontact.pipeline.run_end import cancel_job_rate_timers, where_it_is
from roughcontact.pipeline.targets import (
    WILDCARD_CONSTRAINTS,
    Targets,
    batch_path,
    batch_runtime_min,
    case_path,
    contact_mem_mb,
    contact_path,
    contact_runtime_min,
    map_side,
    surface_mem_mb,
    surface_runtime_min,
    topography_path,
)
from roughcontact.studies.accuracy import variants as accuracy_variants

TARGETS = Targets.from_config(config, accuracy_variants, FIGURES)
SCENES = TARGETS.scenes
ACTIVE_SCENE = TARGETS.active
# An invalid scene stops only a run of it (a target under results/<it>/ names its error); the others plan.
for _message in TARGETS.invalid.values():
    logger.warning(f"roughcontact: {_message} (a run of that scene would stop here)")
# What the active scene computes, before any job runs (a large scene's cost at a glance).
logger.info(plan_summary(ACTIVE_SCENE, SCENES[ACTIVE_SCENE]))


# The plan the scene's ETA is read against (python -m roughcontact.pipeline.progress): the jobs this run
# will run for the active scene, from Snakemake's DAG, each with its benchmark file, log and expected size.
onstart:
    try:
        _under = f"results/{ACTIVE_SCENE}/"
        _jobs = [
            (job.rule.name, str(job.benchmark), next(iter(job.log), None), dict(job.resources).get("runtime"))
            for job in workflow.dag.needrun_jobs()
            if job.benchmark is not None and str(job.benchmark).startswith(_under)
        ]
        write_plan(Path("results", ACTIVE_SCENE), ACTIVE_SCENE, _jobs, workflow.cores)
    except OSError as _err:  # a read-only or full results/<scene>: one line, before any job runs
        logger.error(
            f"roughcontact: {one_line(_err)}; the run writes under results/{ACTIVE_SCENE}/: make it writable "
            "(or free space), then run again"
        )
        raise SystemExit(1)


# Snakemake's job-rate timer (profiles/default: once a minute) would hold the process up to a minute
# after the last job (roughcontact.pipeline.run_end). A run that succeeds ends saying where its result is.
onsuccess:
    cancel_job_rate_timers()
    if not workflow.dryrun:
        for _line in where_it_is(
            Path("results", ACTIVE_SCENE),
            ACTIVE_SCENE,
            drawn=len(TARGETS.scene_figures(SCENES[ACTIVE_SCENE])),
        ):
            logger.info(f"roughcontact: {_line}")


onerror:
    cancel_job_rate_timers()


wildcard_constraints:
    **WILDCARD_CONSTRAINTS,


# The functions the rules name (roughcontact.pipeline.targets.Targets, bound to this config).
scene_of = TARGETS.scene_of
patch_names = TARGETS.patch_names
study_block = TARGETS.study_block
case_input = TARGETS.case_input
contact_input = TARGETS.contact_input
contact_params = TARGETS.contact_params
contact_surface_params = TARGETS.contact_surface_params
contact_cases = TARGETS.contact_cases
contact_kind = TARGETS.contact_kind
contact_tasks = TARGETS.contact_tasks
contact_threads = TARGETS.contact_threads
contact_mpi = TARGETS.contact_mpi
contact_bundle = TARGETS.contact_bundle
contact_job_mem_mb = TARGETS.contact_job_mem_mb
contact_job_mem_mb_per_cpu = TARGETS.contact_job_mem_mb_per_cpu
contact_job_runtime_min = TARGETS.contact_job_runtime_min
contact_files = TARGETS.contact_files
contact_members_of = TARGETS.contact_members_of
case_params = TARGETS.case_params
case_files = TARGETS.case_files
case_list = TARGETS.case_list
batch_input = TARGETS.batch_input
batch_params = TARGETS.batch_params
batch_files = TARGETS.batch_files
study_params = TARGETS.study_params
topography_file = TARGETS.topography_file
topography_input = TARGETS.topography_input
topography_params = TARGETS.topography_params
measured_mem_mb = TARGETS.measured_mem_mb
figure_inputs = TARGETS.figure_inputs
scene_targets = TARGETS.scene_targets
run_record_inputs = TARGETS.run_record_inputs
report_figure_inputs = TARGETS.report_figure_inputs
accuracy_setting = TARGETS.accuracy_setting
accuracy_input = TARGETS.accuracy_input
accuracy_files = TARGETS.accuracy_files
kappa_gap_setting = TARGETS.kappa_gap_setting
kappa_gap_input = TARGETS.kappa_gap_input
kappa_gap_files = TARGETS.kappa_gap_files


def maybe_temp(path, study):
    """`temp(path)` when the active scene's study sets keep_surfaces: false."""
    return path if TARGETS.keeps_surfaces(study) else temp(path)

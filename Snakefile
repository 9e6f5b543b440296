# roughcontact: the contact mechanics of representative rough surfaces.
# Stages: surfaces -> representativity | contact -> aggregate -> fit -> figures.
# `snakemake -j2` runs the default scene (config/config.yaml: scene), `--config scene=NAME`
# another; any single output can be asked for by its path.
from pathlib import Path

from snakemake.utils import min_version

from roughcontact.pipeline.config import SHIPPED_CONFIG, ConfigError, check_config_files
from roughcontact.studies import report as report_module

min_version("9.0")


report: "workflow/report/workflow.rst"


# Report captions render their maths (:math:, .. math::) as MathML: see roughcontact.studies.report.
report_module.render_maths_as_mathml(Path(workflow.basedir, "workflow", "report", "docutils.conf"))


# Snakemake's own message for a config file that is not YAML names neither the file nor the line:
# check every config file once, here, before `configfile:` reads the workflow's own (a file given with
# --configfile is already in workflow.configfiles; `python -m roughcontact.pipeline.config FILE` names the
# line of one of those). The merged config is validated once, in workflow/rules/common.smk.
try:
    check_config_files([*([SHIPPED_CONFIG] if Path(SHIPPED_CONFIG).is_file() else []), *workflow.configfiles])
except ConfigError as err:
    raise WorkflowError(f"invalid config: {err}") from None


configfile: str(SHIPPED_CONFIG)


include: "workflow/rules/common.smk"
include: "workflow/rules/surfaces.smk"
include: "workflow/rules/representativity.smk"
include: "workflow/rules/contact.smk"
include: "workflow/rules/aggregate.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/accuracy.smk"
include: "workflow/rules/kappa_gap.smk"
include: "workflow/rules/report.smk"


localrules:
    all,


rule all:
    default_target: True
    input:
        scene_targets(ACTIVE_SCENE),

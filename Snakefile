# roughcontact: the study of Kumar, Sadeghi & Krousgrill (2006) as a workflow.
# Data flows surfaces -> influence -> contact -> aggregate -> figures.
import os

from snakemake.exceptions import WorkflowError
from snakemake.utils import min_version

from roughcontact.study.config import ConfigError, apply_schema
from roughcontact.study.logs import forward_plan_warnings

min_version("8.0")


# The default study; `--configfile other.yaml` replaces it (not merged).
if not config:

    configfile: os.path.join(workflow.basedir, "config", "config.yaml")


forward_plan_warnings(logger)  # the plan's warnings in Snakemake's log
try:
    apply_schema(config)  # every default filled in; one line per offending key
except ConfigError as err:
    raise WorkflowError(str(err)) from None


report: "report/workflow.rst"


include: "rules/common.smk"
include: "rules/surfaces.smk"
include: "rules/influence.smk"
include: "rules/contact.smk"
include: "rules/audit.smk"
include: "rules/reports.smk"
include: "rules/figures.smk"


rule all:
    default_target: True
    input:
        get_final_outputs(),

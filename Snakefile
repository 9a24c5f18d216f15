# roughcontact: the study of Kumar, Sadeghi & Krousgrill (2006) as a workflow.
# Data flows surfaces -> influence -> contact -> aggregate -> figures.
import os

from snakemake.utils import min_version, validate

min_version("8.0")


# The default study; `--configfile other.yaml` replaces it (not merged).
if not config:

    configfile: os.path.join(workflow.basedir, "config", "config.yaml")


validate(config, "config/schema.yaml")


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

"""Snakemake entry point of rule `contact`: one surface cell on one geometry."""

from roughcontact.study.config import ContactSettings
from roughcontact.study.jobs import solve_contact_job
from roughcontact.study.logs import route_logging
from roughcontact.study.records import ContactJob

route_logging(snakemake.log[0])
solve_contact_job(
    ContactJob.from_params(snakemake.params.job),
    snakemake.input.surfaces,
    snakemake.input.influence,
    snakemake.output[0],
    ContactSettings.from_section(snakemake.params.solver),
    config=snakemake.config,
)

"""Snakemake entry point of rule `contact`: one surface cell on one geometry."""

from roughcontact.logs import route_logging
from roughcontact.pipeline import solve_contact_job

route_logging(snakemake.log[0])
solve_contact_job(
    snakemake.params.job,
    snakemake.input.surfaces,
    snakemake.input.influence,
    snakemake.output[0],
    snakemake.params.solver,
    config=snakemake.config,
)

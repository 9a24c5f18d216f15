"""Snakemake entry point of rule `contact`: one surface cell on one geometry."""

from roughcontact.study.contact_jobs import solve_contact_job
from roughcontact.study.logs import route_logging

route_logging(snakemake.log[0])
solve_contact_job(
    snakemake.params.job,
    # the job's files by input name (ContactJob.files: surfaces, influence, a counter body's)
    dict(snakemake.input.items()),
    snakemake.output[0],
    snakemake.params.solver,
    config=snakemake.config,
)

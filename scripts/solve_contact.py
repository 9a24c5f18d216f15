"""Snakemake entry point of rule `contact`: one surface cell on one geometry."""

from roughcontact.study.contact_jobs import solve_contact_job
from roughcontact.study.logs import route_logging

route_logging(snakemake.log[0])
solve_contact_job(
    snakemake.params.job,
    snakemake.input.surfaces,
    snakemake.input.influence,
    snakemake.output[0],
    snakemake.params.solver,
    config=snakemake.config,
    # a counter body's files (Eq 17-18), when the job has one
    counter_surfaces_path=snakemake.input.get("counter_surfaces"),
    counter_influence_path=snakemake.input.get("counter_influence"),
)

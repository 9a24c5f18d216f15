"""Snakemake entry point of rule `cycle`: one capped cell along its loading path."""

from roughcontact.study.jobs.cycles import solve_cycle_job
from roughcontact.study.logs import route_logging
from roughcontact.study.provenance import RunInfo

route_logging(snakemake.log[0])
solve_cycle_job(
    snakemake.params.job,
    # the job's files by input name (CycleJob.files: its contact job's)
    dict(snakemake.input.items()),
    snakemake.output[0],
    snakemake.params.solver,
    run=RunInfo.of(snakemake.config),
)

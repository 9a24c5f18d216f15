"""Snakemake entry point of rule `figure`: execute a figure notebook with papermill."""

from roughcontact.reports.execution import execute_figure
from roughcontact.study.logs import route_logging

route_logging(snakemake.log[0])
execute_figure(
    snakemake.input.notebook,
    snakemake.output.notebook,
    dict(snakemake.params.parameters, png=snakemake.output.png, pdf=snakemake.output.pdf),
    answers=snakemake.output.answers,
    log_path=snakemake.log[0],
)

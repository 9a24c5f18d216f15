"""Snakemake entry point of rule `figure`: execute a figure notebook with papermill."""

from roughcontact.logs import route_logging
from roughcontact.plotting import execute_notebook

route_logging(snakemake.log[0])
execute_notebook(
    snakemake.input.notebook,
    snakemake.output.notebook,
    dict(snakemake.params.parameters, png=snakemake.output.png, pdf=snakemake.output.pdf),
    log_path=snakemake.log[0],
)

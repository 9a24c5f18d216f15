"""Snakemake entry point of checkpoint `influence_choice`: resolve an operator: auto geometry."""

from roughcontact.study.jobs import choose_influence
from roughcontact.study.logs import route_logging

route_logging(snakemake.log[0])
choose_influence(
    snakemake.params.geometry,
    snakemake.params.planned,
    snakemake.input[0],
    snakemake.output[0],
    config=snakemake.config,
)

"""Snakemake entry point of rule `pair_influence`: two bodies' influence models summed once."""

from roughcontact.study.jobs import build_pair
from roughcontact.study.logs import route_logging

route_logging(snakemake.log[0])
build_pair(
    snakemake.params.pair,
    snakemake.input.first,
    snakemake.input.second,
    snakemake.output[0],
    config=snakemake.config,
)

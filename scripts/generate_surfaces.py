"""Snakemake entry point of rule `surfaces`: generate (or import, if measured) one surface cell."""

from roughcontact.logs import route_logging
from roughcontact.pipeline import build_surface_cell

route_logging(snakemake.log[0])
build_surface_cell(
    snakemake.params.cell,
    snakemake.params.study_seed,
    snakemake.output[0],
    config=snakemake.config,
)

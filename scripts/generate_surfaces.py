"""Snakemake entry point of rule `surfaces`: generate (or import, if measured) one surface
cell, or take its surfaces from a larger cell's file."""

from roughcontact.study.logs import route_logging
from roughcontact.study.surface_jobs import build_surface_cell

route_logging(snakemake.log[0])
build_surface_cell(
    snakemake.params.cell,
    snakemake.params.study_seed,
    snakemake.output[0],
    config=snakemake.config,
    source=snakemake.params.source,
    source_path=snakemake.input.get("source"),
)

"""Snakemake entry point of rule `grid_convergence_surfaces`: the study's surfaces on one grid."""

from roughcontact.study.jobs.grid_convergence import build_grid_surfaces
from roughcontact.study.logs import route_logging
from roughcontact.study.provenance import RunInfo

route_logging(snakemake.log[0])
build_grid_surfaces(
    snakemake.params.settings,
    snakemake.params.study_seed,
    int(snakemake.wildcards.gcgrid),
    snakemake.output[0],
    run=RunInfo.of(snakemake.config),
)

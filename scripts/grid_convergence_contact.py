"""Snakemake entry point of rule `grid_convergence_contact`: the sweeps on one grid."""

from roughcontact.study.jobs.grid_convergence import solve_grid
from roughcontact.study.logs import route_logging
from roughcontact.study.provenance import RunInfo

route_logging(snakemake.log[0])
solve_grid(
    snakemake.params.settings,
    snakemake.input[0],
    int(snakemake.wildcards.gcgrid),
    snakemake.output[0],
    run=RunInfo.of(snakemake.config),
)

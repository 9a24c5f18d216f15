"""Snakemake entry point of rule `grid_convergence`: the table and figure of the study."""

from roughcontact.reports.grid_convergence import grid_convergence_report
from roughcontact.study.logs import route_logging

route_logging(snakemake.log[0])
grid_convergence_report(list(snakemake.input), snakemake.output.csv, snakemake.output.png)

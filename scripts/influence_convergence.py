"""Snakemake entry point of rule `influence_convergence`: mesh presets compared."""

import dataclasses
import logging

from roughcontact.reports.convergence import influence_convergence, plot_influence_convergence
from roughcontact.study.config import ConvergenceSettings
from roughcontact.study.jobs.storage import check_parameters
from roughcontact.study.logs import route_logging
from roughcontact.study.provenance import atomic_path
from roughcontact.study.records import Geometry
from roughcontact.units import MPA

route_logging(snakemake.log[0])
log = logging.getLogger("roughcontact.report")
settings = ConvergenceSettings.from_section(snakemake.params.settings)
body = Geometry.from_params(snakemake.params.geometry)
for mesh, path in snakemake.params.stored.items():  # each made for the body with that mesh
    check_parameters(path, geometry=dataclasses.replace(body, mesh=mesh).params())
base = body.block(E=snakemake.params.E_MPa * MPA)
table = influence_convergence(base, settings, stored=snakemake.params.stored, progress=log.info)
with atomic_path(snakemake.output.csv) as tmp:
    table.to_csv(tmp, index=False)
with atomic_path(snakemake.output.png) as tmp:
    plot_influence_convergence(table, tmp)

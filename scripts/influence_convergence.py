"""Snakemake entry point of rule `influence_convergence`: mesh presets compared."""

import logging

from roughcontact.reports.convergence import influence_convergence, plot_influence_convergence
from roughcontact.study.cells import block_geometry
from roughcontact.study.logs import route_logging
from roughcontact.study.provenance import atomic_path

route_logging(snakemake.log[0])
log = logging.getLogger("roughcontact.report")
settings = snakemake.params.settings
base = block_geometry(snakemake.params.geometry, E=snakemake.params.E_MPa * 1e6)
table = influence_convergence(
    base,
    settings.get("presets", ["paper", "graded", "refined", "converged"]),
    surfaces=settings.get("surfaces", 3),
    sigma=settings.get("sigma_um", 24.5) * 1e-6,
    corr_length=settings.get("b_mm", 1.0) * 1e-3,
    pressures=[p * 1e6 for p in settings.get("pressures_MPa", [0.3, 1.0, 2.0])],
    progress=log.info,
    stored=snakemake.params.stored,
)
with atomic_path(snakemake.output.csv) as tmp:
    table.to_csv(tmp, index=False)
with atomic_path(snakemake.output.png) as tmp:
    plot_influence_convergence(table, tmp)

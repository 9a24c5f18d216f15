"""Snakemake entry point of rule `speed_vs_error`: the speed-against-error report."""

import logging

from roughcontact.reports.speed import speed_vs_error_report
from roughcontact.study.logs import route_logging

route_logging(snakemake.log[0])
geometry = snakemake.params.geometry
settings = dict(snakemake.params.settings)
if "pressures_MPa" in settings:
    settings["pressures"] = [p * 1e6 for p in settings.pop("pressures_MPa")]
speed_vs_error_report(
    snakemake.output.md,
    snakemake.output.csv,
    [snakemake.output.png, snakemake.output.counts_png],
    out_presets=snakemake.output.presets,
    grid=geometry["grid"][0],
    size=geometry["size_mm"][0] * 1e-3,
    thickness=geometry["thickness_mm"] * 1e-3,
    E=snakemake.params.E_MPa * 1e6,
    nu=geometry["nu"],
    mesh_table_path=snakemake.input.mesh_table,
    seed=snakemake.params.study_seed,
    progress=logging.getLogger("roughcontact.report").info,
    **settings,
)

"""Snakemake entry point of rule `speed_vs_error`: the speed-against-error report."""

import logging

from roughcontact.reports.speed import speed_vs_error_report
from roughcontact.study.config import SpeedReportSettings
from roughcontact.study.logs import route_logging
from roughcontact.study.records import Geometry
from roughcontact.study.sources import spectrum_from_entry
from roughcontact.units import MPA

route_logging(snakemake.log[0])
settings = SpeedReportSettings.from_section(snakemake.params.settings)
body = Geometry.from_params(snakemake.params.geometry).block(E=snakemake.params.E_MPa * MPA)
spectrum = spectrum_from_entry(snakemake.params.settings.get("spectrum"))
speed_vs_error_report(
    snakemake.output.md,
    snakemake.output.csv,
    [snakemake.output.png, snakemake.output.counts_png],
    out_presets=snakemake.output.presets,
    grid=body.grid[0],
    size=body.size[0],
    thickness=body.thickness,
    E=body.E,
    nu=body.nu,
    mesh_table_path=snakemake.input.mesh_table,
    seed=snakemake.params.study_seed,
    spectrum=None if spectrum is None else spectrum.spec_fields(),
    progress=logging.getLogger("roughcontact.report").info,
    **settings.as_kwargs(),
)

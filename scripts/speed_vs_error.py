"""Snakemake entry point of rule `speed_vs_error`: the speed-against-error report."""

import logging

from roughcontact.reports.speed import (
    CellSurfaces,
    ReportFiles,
    SpeedOptions,
    SpeedSpecimen,
    speed_vs_error_report,
)
from roughcontact.study.config import SpeedReportSettings
from roughcontact.study.logs import route_logging
from roughcontact.study.records import Geometry
from roughcontact.study.sources import spectrum_from_entry
from roughcontact.units import MPA

route_logging(snakemake.log[0])
settings = SpeedReportSettings.from_section(snakemake.params.settings)
body = Geometry.from_params(snakemake.params.geometry).block(E=snakemake.params.E_MPa * MPA)
spectrum = spectrum_from_entry(snakemake.params.settings.get("spectrum"))
files = ReportFiles(
    md=snakemake.output.md,
    csv=snakemake.output.csv,
    png=[snakemake.output.png, snakemake.output.counts_png],
    presets=snakemake.output.presets,
    mesh_table=snakemake.input.mesh_table,
)
specimen = SpeedSpecimen.of_block(body, generator=CellSurfaces(seed=snakemake.params.study_seed))
options = SpeedOptions(grid_spectrum=None if spectrum is None else spectrum.spec_fields())
speed_vs_error_report(
    files, settings, specimen, options, progress=logging.getLogger("roughcontact.report").info
)

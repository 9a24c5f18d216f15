"""Snakemake entry point of rule `aggregate`: a figure's or sweep's tables."""

from roughcontact.study import layout
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.jobs.aggregation import aggregate_study
from roughcontact.study.logs import route_logging
from roughcontact.study.probes import study_probes_from_params
from roughcontact.study.provenance import RunInfo

route_logging(snakemake.log[0])
cells = [StudyCell.from_params(params) for params in snakemake.params.cells]
paths = {cell.contact_key: layout.contact(cell.contact_key) for cell in cells}
missing = sorted(set(paths.values()) - set(snakemake.input))
if missing:
    raise RuntimeError(f"contact files not among the rule's inputs: {missing}")
aggregate_study(
    cells,
    paths,
    snakemake.params.levels,
    snakemake.output.table,
    snakemake.output.moduli,
    snakemake.output.meta,
    run=RunInfo.of(snakemake.config),
    validity_path=snakemake.output.validity,
    probes=study_probes_from_params(snakemake.params.probes),
)

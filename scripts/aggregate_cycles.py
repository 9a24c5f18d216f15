"""Snakemake entry point of rule `aggregate_cycles`: a study's loops, per step and cycle."""

from roughcontact.study.contact_records import StudyCell
from roughcontact.study.cycle_records import LoadingSettings
from roughcontact.study.jobs.cycle_aggregation import aggregate_cycles
from roughcontact.study.logs import route_logging
from roughcontact.study.probes import study_probes_from_params
from roughcontact.study.provenance import RunInfo

route_logging(snakemake.log[0])
cells = [StudyCell.from_params(params) for params in snakemake.params.cells]
loading = LoadingSettings.from_params(snakemake.params.loading)
paths = {loading.job(cell).key: loading.job(cell).output for cell in cells}
missing = sorted(set(paths.values()) - set(snakemake.input))
if missing:
    raise RuntimeError(f"cycle files not among the rule's inputs: {missing}")
aggregate_cycles(
    cells,
    loading,
    paths,
    snakemake.output,
    run=RunInfo.of(snakemake.config),
    probes=study_probes_from_params(snakemake.params.probes),
)

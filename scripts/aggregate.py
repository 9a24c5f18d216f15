"""Snakemake entry point of rule `aggregate`: a figure's or sweep's tables."""

from roughcontact.study.aggregation import aggregate_study
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.logs import route_logging
from roughcontact.study.probes import study_probes

route_logging(snakemake.log[0])
cells = [StudyCell.from_params(params) for params in snakemake.params.cells]
paths = {cell.contact_key: f"results/contact/{cell.contact_key}.h5" for cell in cells}
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
    config=snakemake.config,
    validity_path=snakemake.output.validity,
    probes=study_probes(snakemake.config),
)

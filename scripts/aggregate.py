"""Snakemake entry point of rule `aggregate`: a figure's or sweep's tables."""

from roughcontact.study.cells import contact_key
from roughcontact.study.jobs import aggregate_study
from roughcontact.study.logs import route_logging

route_logging(snakemake.log[0])
cells = snakemake.params.cells
paths = {contact_key(c): f"results/contact/{contact_key(c)}.h5" for c in cells}
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
)

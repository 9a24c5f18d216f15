"""Snakemake entry point of rule `audit`: one row per study cell, flagged cells first."""

from roughcontact.reports.audit import audit_table, write_audit
from roughcontact.study.logs import route_logging
from roughcontact.study.provenance import config_hash

route_logging(snakemake.log[0])
table = audit_table(snakemake.params.studies, levels=snakemake.params.levels,
                    study_seed=snakemake.config["study_seed"])
write_audit(table, snakemake.output.csv, snakemake.output.md,
            config_hash=config_hash(snakemake.config))
flagged = table[table["flagged"]]
for _, row in flagged.iterrows():
    print(f"FLAGGED {row['study']} cell {row['cell']}: {row['flags']}")
print(f"audit: {len(table)} cells, {len(flagged)} flagged -> {snakemake.output.md}")

"""Snakemake entry point of rule `audit_verify`: re-solve a seeded sample and compare."""

from roughcontact.reports.audit import verify_sample
from roughcontact.study.logs import route_logging
from roughcontact.study.provenance import atomic_path

route_logging(snakemake.log[0])
table = verify_sample(snakemake.params.jobs, snakemake.params.sample, snakemake.params.seed,
                      snakemake.config["contact"], study_seed=snakemake.config["study_seed"])
with atomic_path(snakemake.output[0]) as tmp:
    table.to_csv(tmp, index=False)
bad = table[~table["ok"]]
for _, row in bad.iterrows():
    print(f"MISMATCH {row['contact_job']} surfaces {row['surfaces']}: "
          f"max relative difference {row['max_relative_difference']:.3g}")
print(f"audit_verify: {len(table)} batches re-solved, {len(bad)} mismatches")

"""Snakemake entry point of rule `audit_strict`: fail when the audit flagged any cell."""

import sys

import pandas as pd

from roughcontact.study.logs import route_logging
from roughcontact.study.provenance import atomic_path

route_logging(snakemake.log[0])
table = pd.read_csv(snakemake.input[0], dtype={"flags": str})
flagged = table[table["flags"].fillna("") != ""]
if len(flagged):
    lines = [f"  {r['study']} cell {r['cell']} ({r['contact_job']}): {r['flags']}"
             for _, r in flagged.iterrows()]
    sys.exit(f"audit (strict): {len(flagged)} of {len(table)} cells flagged; see "
             f"{snakemake.input[0]}:\n" + "\n".join(lines))
with atomic_path(snakemake.output[0]) as tmp:
    with open(tmp, "w") as f:
        f.write(f"{len(table)} cells, none flagged\n")

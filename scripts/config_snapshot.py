"""Snakemake entry point of rule `config_snapshot`: the run's configuration, for the report."""

import yaml

from roughcontact.study.provenance import atomic_path, config_hash

config = dict(snakemake.config)
with atomic_path(snakemake.output[0]) as tmp:
    with open(tmp, "w") as f:
        f.write(f"# the configuration of this run (hash {config_hash(config)})\n")
        yaml.safe_dump(config, f, sort_keys=False)

"""Snakemake entry point of rule `thermal_influence`: a block's thermal influence k R."""

import os

from roughcontact.study.jobs.thermal import build_thermal
from roughcontact.study.logs import route_logging
from roughcontact.study.provenance import RunInfo

route_logging(snakemake.log[0])
# the sparse factorization is the one multithreaded step of the build
os.environ["MKL_NUM_THREADS"] = str(snakemake.threads)
build_thermal(
    snakemake.params.thermal,
    snakemake.output[0],
    solver=snakemake.params.solver,
    run=RunInfo.of(snakemake.config),
)

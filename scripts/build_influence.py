"""Snakemake entry point of rule `influence`: build and store E * C of one geometry."""

import os

from roughcontact.study.jobs import build_influence
from roughcontact.study.logs import route_logging

route_logging(snakemake.log[0])
# the sparse factorization is the one multithreaded step of the pipeline
os.environ["MKL_NUM_THREADS"] = str(snakemake.threads)
build_influence(
    snakemake.params.geometry,
    snakemake.output[0],
    solver=snakemake.params.solver,
    max_memory_gb=snakemake.params.max_memory_gb,
    config=snakemake.config,
)

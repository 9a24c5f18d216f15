"""The surfaces job's entry point, where its rule's script imports it from.

The job is :func:`roughcontact.study.jobs.surfaces.build_surface_cell`; this module
keeps the import path of ``scripts/generate_surfaces.py``, whose text must not
change: Snakemake reruns every job whose script is newer than its outputs (and every
contact job after it).
"""

from roughcontact.study.jobs.surfaces import build_surface_cell

__all__ = ["build_surface_cell"]

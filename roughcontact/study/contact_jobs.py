"""The contact job's entry point, where its rule's script imports it from.

The job is :func:`roughcontact.study.jobs.contact.solve_contact_job`; this module
keeps the import path of ``scripts/solve_contact.py``, whose text must not change:
Snakemake reruns every job whose script is newer than its outputs, and a study's
stored contact results would be solved again for nothing.
"""

from roughcontact.study.jobs.contact import solve_contact_job

__all__ = ["solve_contact_job"]

"""The bodies of the workflow's jobs: each reads its files, checked, and writes one result.

Runs in a job (a rule's script), never at plan time: no module here imports the
plan (:mod:`roughcontact.study.plan`; an import-linter contract holds it). A job
takes its rule's params, turns them into its records once (its edge), and works on
those::

    from roughcontact.study.jobs.contact import solve_contact_job
    solve_contact_job(job.params(), job.paths(), "out.h5", study.contact.params())

``surfaces`` generates or imports a surface cell, ``influence`` builds an influence
model, a pair of them or the choice of ``operator: auto``, ``contact`` sweeps a
contact job, ``aggregation`` averages a study's cells into its tables,
``grid_convergence`` the on-demand grid study; ``storage`` has one reader and one
writer per stored file kind, each read checked against what the job expects.
"""

#: The influence jobs, where their rules' scripts import them from (``scripts/
#: build_influence.py`` ...): imported when asked for, so that a job that only reads a
#: file (:mod:`~roughcontact.study.jobs.storage`) loads neither the finite-element
#: model nor the solvers.
_INFLUENCE_JOBS = ("build_influence", "build_pair", "choose_influence")

__all__ = list(_INFLUENCE_JOBS)


def __getattr__(name: str):
    if name in _INFLUENCE_JOBS:
        from roughcontact.study.jobs import influence

        return getattr(influence, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

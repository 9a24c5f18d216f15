"""The plan of a study: what a configuration asks the workflow to make, checked before any job.

Runs when the workflow is planned (``rules/common.smk``), never in a job::

    from roughcontact.study.settings import load_study
    from roughcontact.study.plan.cells import study_plan

    plan = study_plan(load_study("config/quick.yaml"))  # checks, then every record
    job = next(iter(plan.jobs.values()))                 # a contact job
    job.paths()                                          # the files it reads

``studies`` turns each contact figure or sweep of the
:class:`~roughcontact.study.settings.Study` into study cells (its counter bodies by
``counter_entries``), ``cells`` makes the :class:`~roughcontact.study.plan.cells.StudyPlan`
after the checks the schema cannot make (``checks``, ``block_checks``,
``body_checks``, ``counter_checks``, ``measured_checks``); ``figures`` is the figure
registry (each figure's kind, surfaces and caption, ``captions``); ``resources`` the
memory and time each job asks a scheduler for.
"""

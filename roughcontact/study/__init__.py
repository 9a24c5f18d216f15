"""Stage 4, study: from a configuration to stored, traceable results.

Split by when it runs: the records both sides share live here, the plan
(:mod:`roughcontact.study.plan`, when the workflow is planned) and the jobs
(:mod:`roughcontact.study.jobs`, in a rule's script) in their subpackages; job code
never imports the plan (an import-linter contract). A run, from the configuration
to a contact job's result::

    from roughcontact.study.settings import load_study
    from roughcontact.study.plan.cells import study_plan

    study = load_study("config/quick.yaml")    # validated, typed, SI (the edge)
    plan = study_plan(study)                   # checked; every job as a record
    job = plan.jobs[next(iter(plan.jobs))]     # its params() go to its rule
    job.paths()                                # the files it reads (layout)

The shared records: ``config`` validates a configuration against the schema (which
fills every default) and holds the settings records of its sections in SI units;
``settings`` makes the one :class:`~roughcontact.study.settings.Study` of them;
``records``, ``contact_records`` and ``counter_records`` are the frozen records of
surface cells, geometries, study cells, contact jobs and counter bodies, each with
its file key and plain ``params()`` (``codec``: written and read back from the
fields, each declaring its key and unit once); ``sources`` measured files and spectra;
``layout`` the ``results/`` layout; ``probes`` the one registry of the probes a
contact job records (the flow: ``flow_settings``); ``provenance`` the version, commit
and configuration hash of every output; ``presets`` the measured accuracy presets;
``memory_advice`` the keys that bring an influence build within memory.
"""

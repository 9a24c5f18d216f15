"""Stage 4, study: from a configuration to stored, traceable results.

``config`` validates a configuration (the schema fills every default) and
turns its settings into SI units; ``studies`` turns each contact figure or
sweep into typed records (``records``: surface cells, geometries, study
cells, contact jobs; ``sources``: measured files and spectra), ``checks``
refuses what the schema cannot, and ``cells`` makes the plan of every job
and file key a configuration asks for, once (``cells.study_plan``); ``surface_jobs``
are the bodies of the workflow's surface jobs, ``jobs`` of its influence and
contact jobs, ``aggregation`` of its aggregation; ``probes`` the one registry of
the probes a contact job records (the flow, ``flow_settings``) and what the
aggregation adds to their columns; ``storage`` has one reader and
one writer per stored file kind, with their content hashes; ``provenance`` the version, commit and
config hash of every output; ``resources`` the memory and time each job asks
a scheduler for; ``presets`` the measured accuracy presets.
"""

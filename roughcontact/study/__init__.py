"""Stage 4, study: from a configuration to stored, traceable results.

``config`` turns a validated configuration into typed settings in SI units;
``cells`` names the surface cells, geometries and contact jobs a
configuration asks for (and their file keys); ``jobs`` are the bodies of the
workflow's jobs (surfaces, influence, contact, aggregation); ``storage`` has
one reader and one writer per stored file kind, with their content hashes;
``provenance`` the version, commit and config hash of every output;
``resources`` the memory and time each job asks a scheduler for; ``presets``
the measured accuracy presets.
"""

"""Stage 5, reports: what the study and its numerical model are worth.

``convergence`` compares the mesh presets (influence entries and contact
results); ``speed`` measures speed against error of the solver, the grid and
the number of surfaces and recommends settings; ``audit`` checks every study
cell's provenance and a seeded re-solve; ``plotting`` draws and saves the
figures; ``execution`` runs the papermill notebooks (in the job's process,
through ``notebook_engine``) and removes what killed writers left.
"""

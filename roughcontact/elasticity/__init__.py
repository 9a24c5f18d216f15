"""Stage 2, elasticity: how the body deflects under pressure on its contact grid.

``fem`` assembles and condenses the finite block (scikit-fem); ``influence``
holds the block's geometry, mesh presets, cost estimate and the dense
influence matrix E * C; ``halfspace`` is Love's elastic half-space (dense and
periodic FFT operators); ``operators`` the matrix-free block operator (Love
plus a coarse finite-element correction) and the rule that picks a model;
``protocol`` the interface all of them offer the contact solver
(``InfluenceOperator``) and the dense-matrix and adapter implementations.
Nothing here knows about surfaces, contact or the workflow.
"""

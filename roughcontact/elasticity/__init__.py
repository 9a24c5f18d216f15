"""Stage 2, elasticity: how the body deflects under pressure on its contact grid.

The finite block, one room per step (scikit-fem): ``mesh`` (the structured
hexahedral mesh, its slabs and node numbering), ``elements`` (one box
element's stiffness and top face), ``dofs`` (support conditions and
hanging-node ties), ``assembly`` (the stiffness and the top-face load and
observation operators) and ``sparse_solve`` (the condensation ``R K^-1 F^T``
by PARDISO or SuperLU). ``influence`` holds the block's geometry, mesh
presets, cost estimate and the dense influence matrix E * C; ``halfspace`` is
Love's elastic half-space (dense and periodic FFT operators) and the spectral
periodic half-space of the peers; ``transforms`` the pruned, float32/float64
FFT products they share; ``operators``
the matrix-free block operator (Love plus a coarse finite-element correction)
and the rule that picks a model; ``protocol`` the interface all of them offer
the contact solver (``InfluenceOperator``) and the dense-matrix and adapter
implementations. Nothing here knows about surfaces, contact or the workflow.
"""

"""Stage 3, contact: a rigid flat pressed onto rough surfaces on an elastic body.

``solver`` minimizes the complementary energy with p >= 0 (Eq 27 of Kumar
et al. 2006) for one or many surfaces and through approach sweeps; ``nondim``
solves a cell once in dimensionless form and rescales it to any sigma and E
(Eq 28-32); ``aggregate`` averages a cell's surfaces at equal nominal
pressure; ``cell`` is the one sweep-then-aggregate recipe the workflow, the
reports and the audit share; ``halfspace_criterion`` measures, by solving,
whether the half-space model is enough for a geometry.

The solver's public names are re-exported here, so ``from roughcontact import
contact; contact.solve(...)`` works as it always has.
"""

from roughcontact.contact.solver import (
    METHODS,
    PRECISIONS,
    ContactResult,
    SweepResult,
    kkt_residual,
    solve,
    solve_many,
    sweep,
    tangent_stiffness,
)

__all__ = [
    "METHODS",
    "PRECISIONS",
    "ContactResult",
    "SweepResult",
    "kkt_residual",
    "solve",
    "solve_many",
    "sweep",
    "tangent_stiffness",
]

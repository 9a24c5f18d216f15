"""Transport: what flows through the gap of a contact interface.

``flow`` solves the steady Reynolds equation with the local cubic law on a gap
field and reads off its effective conductance, flow factors (Patir & Cheng
1978), leak rate and whether the free space percolates; ``probe`` is what a contact sweep
records of it at every step (:class:`FlowProbe`, :data:`NO_FLOW`); ``references`` holds the
closed forms it is checked against (a flat channel, series and parallel gaps,
the Keller-Dykhne checkerboard) and Patir & Cheng's fitted flow factors.

The stage needs only gap fields (plain arrays, m) and numpy/scipy: it imports
no other stage, and sits in the lowest stage layer beside ``surfaces`` and
``elasticity`` (checked by ``lint-imports``). The contact stage will call it on
its solutions' gaps through a value it is given, so contact depends on
transport and never the other way round.
"""

from roughcontact.transport.flow import (
    ARITHMETIC,
    DIRECT,
    FACE_RULES,
    FLOW_DIRECTIONS,
    HARMONIC,
    PERIODIC,
    SEALED,
    BandedCholesky,
    DirectSolver,
    FaceRule,
    FlowResult,
    FlowSetup,
    JacobiCG,
    Seal,
    Sides,
    solve_flow,
)
from roughcontact.transport.probe import (
    FLOW_COLUMNS,
    FLOW_UNITS,
    NO_FLOW,
    SIDE_CHOICES,
    FlowProbe,
    flow_column_names,
)

__all__ = [
    "ARITHMETIC",
    "DIRECT",
    "FACE_RULES",
    "FLOW_COLUMNS",
    "FLOW_DIRECTIONS",
    "FLOW_UNITS",
    "HARMONIC",
    "NO_FLOW",
    "PERIODIC",
    "SEALED",
    "SIDE_CHOICES",
    "BandedCholesky",
    "DirectSolver",
    "FaceRule",
    "FlowProbe",
    "FlowResult",
    "FlowSetup",
    "JacobiCG",
    "Seal",
    "Sides",
    "flow_column_names",
    "solve_flow",
]

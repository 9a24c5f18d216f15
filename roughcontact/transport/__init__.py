"""Transport: what flows through the gap of a contact interface.

``flow`` solves the steady Reynolds equation with the local cubic law on a gap
field and reads off its effective conductance, flow factors (Patir & Cheng
1978), leak rate and whether the free space percolates; ``references`` holds the
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
    DirectSolver,
    FaceRule,
    FlowResult,
    FlowSetup,
    JacobiCG,
    Seal,
    Sides,
    solve_flow,
)
from roughcontact.transport.references import (
    PATIR_CHENG_PRESSURE_FLOW,
    PatirChengFit,
    checkerboard_conductance,
    flat_channel_conductance,
    parallel_conductance,
    patir_cheng_phi_x,
    series_conductance,
)

__all__ = [
    "ARITHMETIC",
    "DIRECT",
    "FACE_RULES",
    "FLOW_DIRECTIONS",
    "HARMONIC",
    "PATIR_CHENG_PRESSURE_FLOW",
    "PERIODIC",
    "SEALED",
    "DirectSolver",
    "FaceRule",
    "FlowResult",
    "FlowSetup",
    "JacobiCG",
    "PatirChengFit",
    "Seal",
    "Sides",
    "checkerboard_conductance",
    "flat_channel_conductance",
    "parallel_conductance",
    "patir_cheng_phi_x",
    "series_conductance",
    "solve_flow",
]

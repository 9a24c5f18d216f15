"""Transport: what flows through the gap of a contact interface.

``flow`` solves the steady Reynolds equation with the local cubic law on a gap
field and reads off its effective conductance, flow factors (Patir & Cheng
1978), leak rate and whether the free space percolates; ``probe`` is what a
contact sweep records of it at every step (:class:`FlowProbe`, :data:`NO_FLOW`);
``references`` holds the closed forms it is checked against (a flat channel,
series and parallel gaps, the Keller-Dykhne checkerboard) and Patir & Cheng's
fitted flow factors.

The stage needs only gap fields (plain arrays, m) and numpy/scipy: it imports
no other stage, and sits in the lowest stage layer beside ``surfaces`` and
``elasticity`` (checked by ``lint-imports``). The contact stage calls it on its
solutions' gaps through the probe its interface grid carries
(:class:`~roughcontact.contact.interface.InterfaceGrid`), so contact depends on
transport and never the other way round; ``percolation`` reads a sweep's
connectivity off for each surface's sealing point and a cell's threshold.
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
    "FLOW_COLUMNS",
    "FLOW_DIRECTIONS",
    "FLOW_UNITS",
    "HARMONIC",
    "NO_FLOW",
    "PATIR_CHENG_PRESSURE_FLOW",
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
    "PatirChengFit",
    "Seal",
    "Sides",
    "checkerboard_conductance",
    "flat_channel_conductance",
    "flow_column_names",
    "parallel_conductance",
    "patir_cheng_phi_x",
    "series_conductance",
    "solve_flow",
]

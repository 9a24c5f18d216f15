"""Transport: what flows through the gap of a contact interface.

``flow`` solves the steady Reynolds equation with the local cubic law on a gap
field and reads off its effective conductance, flow factors (Patir & Cheng
1978), leak rate and whether the free space percolates; ``probe`` is what a
contact sweep records of it at every step (:class:`FlowProbe`, a
:class:`~roughcontact.contact.probes.Probe`; its columns' names and units, which
live here only); ``references`` holds the closed forms it is checked against (a
flat channel, series and parallel gaps, the Keller-Dykhne checkerboard) and Patir
& Cheng's fitted flow factors.

The flow needs only gap fields (plain arrays, m) and numpy/scipy. The stage sits
above ``contact`` (checked by ``lint-imports``): a sweep is given a
:class:`FlowProbe` among the probes of its interface grid
(:class:`~roughcontact.contact.interface.InterfaceGrid`) and records its columns
without knowing them, so transport depends on contact (for what a probe is,
:mod:`roughcontact.contact.probes`) and never the other way round;
``percolation`` reads a sweep's connectivity off for each surface's sealing point
and a cell's threshold.
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
    FLOW_QUANTITIES,
    LEAK_RATE,
    NO_FLOW,
    SIDE_CHOICES,
    FlowProbe,
    column_name,
    flow_column_names,
    flow_columns,
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
    "FLOW_QUANTITIES",
    "HARMONIC",
    "LEAK_RATE",
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
    "column_name",
    "flat_channel_conductance",
    "flow_column_names",
    "flow_columns",
    "parallel_conductance",
    "patir_cheng_phi_x",
    "series_conductance",
    "solve_flow",
]

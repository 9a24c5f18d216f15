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

``conduction`` (a room of its own) is the heat or current that crosses the
contact spots: the thermal influence of a half-space or of the finite block (a
scalar Laplace problem on the elastic model's meshes) and the spot conductance
of a contact set through it, split into bulk and constriction
(:mod:`roughcontact.transport.conduction`, imported by its own name).
"""

from roughcontact.transport import flow, probe, references
from roughcontact.transport.flow import *  # noqa: F403 (flow.__all__)
from roughcontact.transport.probe import *  # noqa: F403 (probe.__all__)
from roughcontact.transport.references import *  # noqa: F403 (references.__all__)

#: The public names of the stage's modules, from the stage.
__all__ = [*flow.__all__, *probe.__all__, *references.__all__]

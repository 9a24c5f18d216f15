"""Conduction across the interface: thermal and electrical contact conductance.

The influence of a body's contact face on its temperature, as the elasticity
stage's compliance is on its deflection: ``halfspace`` (dense, periodic and
free half-spaces, the kernel ``1 / (2 pi k r)``) and ``block`` (the finite
block's scalar Laplace problem on the elastic model's meshes); ``spot`` the
conductance of a contact set through them (CG on the set, the bulk and
constriction resistances, bodies in series). A walk::

    >>> import numpy as np
    >>> from roughcontact.transport.conduction import halfspace_thermal_influence, spot_conductance
    >>> R = halfspace_thermal_influence((16, 16), (1e-3, 1e-3), conductivity=50.0)
    >>> y, x = np.mgrid[:16, :16] - 7.5
    >>> spot = spot_conductance(R, np.hypot(x, y) < 4.0, element_area=(1e-3 / 16) ** 2)
    >>> bool(abs(spot.conductance / (4 * 50.0 * 4.0 * 1e-3 / 16) - 1) < 0.06)  # Holm, 4 k a
    True

``bodies`` are the bodies heat and current cross (a half-space, the block, two in
series); ``probe`` is what a contact sweep records of it at every step
(:class:`ConductanceProbe`, a :class:`~roughcontact.contact.probes.Probe`: the
conductance of each solution's contact set ``p > 0``; its columns' names and units
live there only); ``correlations`` the industry's correlations it is compared with
(Mikic 1974, Cooper, Mikic & Yovanovich 1969); ``hybrid`` the block's thermal
influence matrix-free beyond 64 x 64 (Love's half-space and a coarse block's
correction; its near field differs from the dense block's, see its docstring).
Nothing here knows about the workflow: the study's settings are
:mod:`roughcontact.study.conductance_settings`.
"""

from roughcontact.transport.conduction import (
    block,
    bodies,
    correlations,
    halfspace,
    hybrid,
    probe,
    spot,
)
from roughcontact.transport.conduction.block import *  # noqa: F403 (block.__all__)
from roughcontact.transport.conduction.bodies import *  # noqa: F403 (bodies.__all__)
from roughcontact.transport.conduction.correlations import *  # noqa: F403 (correlations.__all__)
from roughcontact.transport.conduction.halfspace import *  # noqa: F403 (halfspace.__all__)
from roughcontact.transport.conduction.hybrid import *  # noqa: F403 (hybrid.__all__)
from roughcontact.transport.conduction.probe import *  # noqa: F403 (probe.__all__)
from roughcontact.transport.conduction.spot import *  # noqa: F403 (spot.__all__)

#: The public names of the room's modules.
__all__ = list(dict.fromkeys([*block.__all__, *bodies.__all__, *correlations.__all__,
                             *halfspace.__all__, *hybrid.__all__, *probe.__all__,
                             *spot.__all__]))

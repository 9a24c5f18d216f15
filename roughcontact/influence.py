"""Former name of :mod:`roughcontact.elasticity.influence`, kept so that users' scripts work.

``roughcontact.influence`` *is* that module (same object), private names included.
"""

import sys

from roughcontact.elasticity import influence

sys.modules[__name__] = influence

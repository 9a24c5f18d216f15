"""Former name of :mod:`roughcontact.elasticity.halfspace`, kept so that users' scripts work.

``roughcontact.halfspace`` *is* that module (same object), private names included.
"""

import sys

from roughcontact.elasticity import halfspace

sys.modules[__name__] = halfspace

"""Former name of :mod:`roughcontact.elasticity.operators`, kept so that users' scripts work.

``roughcontact.operators`` *is* that module (same object), private names included.
"""

import sys

from roughcontact.elasticity import operators

sys.modules[__name__] = operators

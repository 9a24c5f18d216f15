"""Former name of :mod:`roughcontact.surfaces.measured`, kept so that users' scripts work.

``roughcontact.measured`` *is* that module (same object), private names included.
"""

import sys

from roughcontact.surfaces import measured

sys.modules[__name__] = measured

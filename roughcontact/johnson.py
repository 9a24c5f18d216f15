"""Former name of :mod:`roughcontact.surfaces.johnson`, kept so that users' scripts work.

``roughcontact.johnson`` *is* that module (same object), private names included.
"""

import sys

from roughcontact.surfaces import johnson

sys.modules[__name__] = johnson

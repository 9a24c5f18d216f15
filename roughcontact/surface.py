"""Former name of :mod:`roughcontact.surfaces.synthetic`, kept so that users' scripts work.

``roughcontact.surface`` *is* that module (same object), private names included.
"""

import sys

from roughcontact.surfaces import synthetic

sys.modules[__name__] = synthetic

"""Former name of :mod:`roughcontact.contact.nondim`, kept so that users' scripts work.

``roughcontact.nondim`` *is* that module (same object), private names included.
"""

import sys

from roughcontact.contact import nondim

sys.modules[__name__] = nondim

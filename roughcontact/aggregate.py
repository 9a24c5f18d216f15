"""Former name of :mod:`roughcontact.contact.aggregate`, kept so that users' scripts work.

``roughcontact.aggregate`` *is* that module (same object), private names included.
"""

import sys

from roughcontact.contact import aggregate

sys.modules[__name__] = aggregate

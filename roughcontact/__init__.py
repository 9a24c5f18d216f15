"""roughcontact: normal contact of rough surfaces on a finite elastic block.

A reproducible implementation of Kumar, Sadeghi & Krousgrill (2006),
"Effect of surface roughness on normal contact compression response",
Proc. IMechE Part J 220, 65-77, with converged alternatives beside it.
"""

from importlib.metadata import PackageNotFoundError, version

from roughcontact.errors import InfeasibleMoments

try:
    __version__ = version("roughcontact")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0+unknown"

__all__ = ["InfeasibleMoments", "__version__"]

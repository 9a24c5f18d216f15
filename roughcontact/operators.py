"""Former name of :mod:`roughcontact.elasticity.operators`, kept so that users' scripts work.

Its names, and those that moved out of it when the library was split by
stage: the half-space criterion (now :mod:`roughcontact.contact.halfspace_criterion`)
and the influence-file storage (now :mod:`roughcontact.study.storage`).
"""

from roughcontact.contact.halfspace_criterion import halfspace_errors, halfspace_meets
from roughcontact.elasticity.operators import (
    COARSE_MAX,
    DENSE_MAX_ELEMENTS,
    HYBRID_MESHES,
    OPERATORS,
    BlockOperator,
    block_operator,
    choose_operator,
    coarsened_side,
    default_coarse_grid,
    halfspace_operator,
    hybrid_operator,
)
from roughcontact.study.storage import influence_datasets as operator_datasets
from roughcontact.study.storage import influence_sha256 as content_sha256
from roughcontact.study.storage import read_influence as read_operator

__all__ = [
    "COARSE_MAX",
    "DENSE_MAX_ELEMENTS",
    "HYBRID_MESHES",
    "OPERATORS",
    "BlockOperator",
    "block_operator",
    "choose_operator",
    "coarsened_side",
    "content_sha256",
    "default_coarse_grid",
    "halfspace_errors",
    "halfspace_meets",
    "halfspace_operator",
    "hybrid_operator",
    "operator_datasets",
    "read_operator",
]

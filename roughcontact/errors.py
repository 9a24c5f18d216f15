"""Exceptions raised by roughcontact."""


class InfeasibleMoments(ValueError):
    """The requested (skewness, kurtosis) cannot be realised.

    Raised when the target lies below the absolute limit Ku >= Sk^2 + 1 (Eq 14
    of Kumar et al. 2006), or, for filtered surfaces, below the reachable
    kurtosis of the linear filter for the given grid and autocorrelation
    (Eq 15 with Eq 12-13). The message states the limit and what to change.
    """


class MeasurementError(ValueError):
    """A measured height map cannot be imported as it stands.

    The message names the file and, where it applies, the line (ragged rows,
    non-numeric values, repeated points), the count and fraction of missing
    points, or the axis and spacings of a non-uniform grid. ``path`` and
    ``line`` (1-based, or None) are kept as attributes.
    """

    def __init__(self, message: str, path=None, line: int | None = None):
        super().__init__(message)
        self.path = None if path is None else str(path)
        self.line = line


class StoredFileError(RuntimeError):
    """A stored result cannot be used: unreadable (truncated, not HDF5), written
    without a content hash, or its content no longer matches the hash written
    with it (changed or damaged since). The message names the file and what to
    do (delete it: the workflow rebuilds it). ``path`` is kept as an attribute.
    """

    def __init__(self, message: str, path=None):
        super().__init__(message)
        self.path = None if path is None else str(path)


class FactorizationError(RuntimeError):
    """The sparse factorization of a finite-element model failed (or had to perturb
    pivots, so its stiffness matrix is not definite).

    The message names the solver, its error code and what the code means, and
    what to change; ``solver`` and ``code`` are kept as attributes. The study's
    influence build adds the geometry and the config keys.
    """

    def __init__(self, message: str, solver: str | None = None, code: int | None = None):
        super().__init__(message)
        self.solver = solver
        self.code = code


class IndefiniteOperator(ValueError):
    """An influence operator is not positive definite (Eq 39), so Eq 27 is not a
    convex problem and a converged solve proves nothing.

    The message names the operator (the file it was read from, where there is
    one) and gives estimates of its smallest and largest eigenvalues, kept as
    the attributes ``smallest`` and ``largest`` (in the unit of the operator's
    entries) beside ``name``.
    """

    def __init__(self, message: str, name: str | None = None, smallest: float | None = None,
                 largest: float | None = None):
        super().__init__(message)
        self.name = name
        self.smallest = smallest
        self.largest = largest


class DiskFullError(OSError):
    """A result cannot be written: the file system holding it is full (or the user's
    quota is). Nothing half-written is left behind. The message names the file, the
    space left, the largest results beside it and what to free; ``path`` is kept as an
    attribute (and ``errno`` is the system's: ENOSPC or EDQUOT).
    """

    def __init__(self, message: str, path=None, errno: int | None = None):
        super().__init__(errno, message)
        self.path = None if path is None else str(path)
        self.message = message

    def __str__(self) -> str:
        return self.message


class FlowNotConverged(RuntimeError):
    """An iterative solve of the flow through a gap (:mod:`roughcontact.transport.flow`)
    did not reach its tolerance in its iterations."""

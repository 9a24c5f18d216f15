"""Exceptions raised by roughcontact."""


class InfeasibleMoments(ValueError):
    """The requested (skewness, kurtosis) cannot be realised.

    Raised when the target lies below the absolute limit Ku >= Sk^2 + 1 (Eq 14
    of Kumar et al. 2006), or, for filtered surfaces, below the reachable
    kurtosis of the linear filter for the given grid and autocorrelation
    (Eq 15 with Eq 12-13). The message states the limit and what to change.
    """

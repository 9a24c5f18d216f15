"""The machine a timing was taken on: one line for the report and the tables' ``attrs``."""

from __future__ import annotations

import math
import os
import platform

__all__ = ["describe_machine"]


def describe_machine() -> str:
    """Architecture, core count, 1-minute load average and the BLAS thread setting.

    Timings of the speed report are wall-clock seconds [s] on a possibly shared
    machine; this line, taken before and after, says how loaded it was.
    """
    load = os.getloadavg() if hasattr(os, "getloadavg") else (math.nan,) * 3
    return (f"{platform.machine()}, {os.cpu_count()} cores, load average {load[0]:.2f}, "
            f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}")

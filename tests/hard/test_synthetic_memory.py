"""Surface generation refuses, before allocating, a grid too large for its memory budget.

A 20000 x 20000 surface used to allocate for about 21 s until numpy failed at
9.5 GB. The generators now estimate the peak of their work arrays from the
spec's shapes and raise SurfaceTooLarge (a MemoryError) when it exceeds
``max_bytes``. The estimate is checked against the peak that tracemalloc
traces while real (small) surfaces are generated.
"""

import logging
import math
import time
import tracemalloc

import numpy as np
import pytest

from roughcontact.surfaces import calibration, exact, memory, synthetic
from roughcontact.surfaces.spec import SurfaceSpec

HUGE = SurfaceSpec(grid=20000, size=1e-2, corr_length=1e-4)
HUGE_PADDED = SurfaceSpec(grid=20000, size=1e-2, corr_length=1e-4, periodic=False)
SMALL = SurfaceSpec(grid=60, size=1e-3, corr_length=1e-4, sigma=1e-6, skew=0.3,
                              kurt=3.5)


def _traced_peak(call):
    """Peak bytes allocated (tracemalloc) while ``call()`` runs, and its exception if any."""
    tracemalloc.start()
    tracemalloc.reset_peak()
    error = None
    try:
        call()
    except MemoryError as raised:
        error = raised
    finally:
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    return peak, error


@pytest.mark.parametrize(
    "call",
    [lambda: synthetic.generate(HUGE, 1),
     lambda: synthetic.generate_many(HUGE, [1, 2, 3]),
     lambda: exact.generate_exact(HUGE, 1),
     lambda: synthetic.generate(HUGE, 1, method="exact"),
     lambda: synthetic.generate(HUGE_PADDED, 1),
     lambda: synthetic.generate(HUGE, 1)],
    ids=["generate", "generate_many", "generate_exact", "exact", "padded", "former_name"],
)
def test_huge_grid_is_refused_fast_without_allocating(call):
    start = time.perf_counter()
    peak, error = _traced_peak(call)
    elapsed = time.perf_counter() - start
    assert isinstance(error, memory.SurfaceTooLarge)
    assert isinstance(error, MemoryError)
    assert elapsed < 1.0
    assert peak < 1e6  # bytes: nothing grid-sized (one 20000 x 20000 float64 is 3.2 GB)
    message = str(error)
    assert "20000 x 20000" in message
    assert "max_bytes" in message and "smaller grid" in message
    # the estimate it states is at least the output, the noise and one complex FFT
    needed = float(message.split("GB (")[1].split(" bytes")[0])
    assert needed >= (8 + 8 + 16) * 20000**2


def test_refusal_follows_max_bytes():
    estimate = memory.estimate_generation_bytes(SMALL)
    with pytest.raises(memory.SurfaceTooLarge, match=r"60 x 60"):
        synthetic.generate(SMALL, 3, max_bytes=0.5 * estimate)
    with pytest.raises(ValueError, match="max_bytes"):
        synthetic.generate(SMALL, 3, max_bytes=-1.0)
    allowed = synthetic.generate(SMALL, 3, max_bytes=estimate)
    unlimited = synthetic.generate(SMALL, 3, max_bytes=math.inf)
    default = synthetic.generate(SMALL, 3)
    assert np.array_equal(allowed, default) and np.array_equal(unlimited, default)
    # more surfaces per call need more
    one = memory.estimate_generation_bytes(SMALL, 1, "paper")
    assert memory.estimate_generation_bytes(SMALL, 10, "paper") > one
    # the calibration's batches are the calibrated filter's peak at small counts
    assert estimate > one


def test_normal_surface_still_generated():
    heights = synthetic.generate(SMALL, 12345)
    assert heights.shape == (60, 60)
    assert np.isfinite(heights).all()
    assert abs(heights.mean()) < 1e-20
    assert 0.5e-6 < heights.std() < 1.5e-6  # sigma = 1 um, sampled over a few correlation cells
    stack = synthetic.generate_many(SMALL, [12345, 7])
    assert np.array_equal(stack[0], heights)


@pytest.mark.parametrize(
    ("spec", "count", "method"),
    [(SurfaceSpec(grid=(256, 192), size=1e-3, corr_length=5e-5), 1, "filter"),
     (SurfaceSpec(grid=(256, 192), size=1e-3, corr_length=5e-5), 3, "filter"),
     (SurfaceSpec(grid=64, size=1e-3, corr_length=1e-4, periodic=False), 2, "filter"),
     (SurfaceSpec(grid=(256, 192), size=1e-3, corr_length=5e-5), 1, "paper"),
     (SurfaceSpec(grid=(256, 192), size=1e-3, corr_length=5e-5), 3, "paper"),
     (SurfaceSpec(grid=64, size=1e-3, corr_length=1e-4, periodic=False), 2, "paper"),
     (SurfaceSpec(grid=(256, 192), size=1e-3, corr_length=5e-5), 2, "exact")],
    ids=["periodic", "periodic-3", "padded-2", "paper", "paper-3", "paper-padded-2", "exact-2"],
)
def test_estimate_matches_the_traced_peak(spec, count, method, caplog):
    seeds = list(range(count))
    calibration._calibrate.cache_clear()  # the calibration's batches are part of the peak
    options = {"max_iter": 5} if method == "exact" else {}
    with caplog.at_level(logging.ERROR):
        peak, error = _traced_peak(
            lambda: synthetic.generate_many(spec, seeds, method=method, **options)
        )
    assert error is None
    estimate = memory.estimate_generation_bytes(spec, count, method)
    assert 0.9 * peak <= estimate <= 1.2 * peak

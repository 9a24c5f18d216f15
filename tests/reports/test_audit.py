"""The audit's check of the realised moments against their targets (no files needed)."""

import numpy as np
import pytest

from roughcontact.reports.audit import EXACT_MOMENT_TOL, MOMENT_SIGMAS, _moment_check


def stats(skew, kurt, sigma=None):
    skew, kurt = np.asarray(skew, float), np.asarray(kurt, float)
    return {"skew": skew, "kurt": kurt,
            "sigma": np.ones_like(skew) if sigma is None else np.asarray(sigma, float)}


def test_realised_moments_are_summarised_with_their_standard_errors():
    out, flags = _moment_check(stats([0.1, -0.1, 0.3, -0.3], [3.0, 3.2, 2.8, 3.0]),
                               {"skew": 0.0, "kurt": 3.0, "method": "filter"})
    assert out["realised_skew_mean"] == pytest.approx(0.0)
    assert out["realised_kurt_se"] == pytest.approx(np.std([3.0, 3.2, 2.8, 3.0], ddof=1) / 2)
    assert out["realised_sigma_z"] != out["realised_sigma_z"]  # no spread: NaN, not judged
    assert list(out)[:3] == ["realised_skew_mean", "realised_skew_se", "realised_skew_z"]
    assert flags == []


@pytest.mark.parametrize("method, note", [("filter", ""),
                                          ("paper", " (paper method: Eq 12-13 uncorrected)")])
def test_a_random_generator_is_flagged_beyond_its_standard_errors(method, note):
    kurt = np.array([3.9, 4.1, 4.0, 4.0])  # 4 against a target of 3: far beyond 3 s.e.
    out, flags = _moment_check(stats([0.0, 0.1, -0.1, 0.0], kurt),
                               {"skew": 0.0, "kurt": 3.0, "method": method})
    assert out["realised_kurt_z"] > MOMENT_SIGMAS
    assert flags == [f"kurt off target{note}"]


def test_the_exact_generator_must_hit_its_targets_to_rounding():
    on = stats([-0.8] * 3, [4.0 + 1e-12] * 3)
    assert _moment_check(on, {"skew": -0.8, "kurt": 4.0, "method": "exact"})[1] == []
    off = stats([-0.8] * 3, [4.0 * (1 + 10 * EXACT_MOMENT_TOL)] * 3)
    assert _moment_check(off, {"skew": -0.8, "kurt": 4.0, "method": "exact"})[1] == [
        "kurt off target"]


def test_a_columns_rounding_is_not_counted_as_a_difference():
    from roughcontact.reports.audit import _relative_difference

    stored, again = np.array([1e-13, 3e-12, 0.0]), np.array([2e-13, 1e-12, 0.0])
    assert _relative_difference(stored, again) > 0.5  # rounding-size values, relative
    assert _relative_difference(stored, again, rounding=1e-9) == 0.0
    # beyond the rounding, the difference counts, relative to at least the rounding
    beyond = _relative_difference(np.array([1e-6]), np.array([3e-6]), rounding=1e-9)
    assert beyond == pytest.approx(2.0)
    nan = _relative_difference(np.array([np.nan, 1.0]), np.array([1.0, 1.0]), rounding=1e-9)
    assert nan == np.inf

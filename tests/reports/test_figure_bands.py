"""Figures: bands of positive quantities stay positive, symbols are typeset.

With 4 surfaces per cell (the quick study) and a large scatter, the
Student-t band of the tables, mean +- t s / sqrt(n) with t = 3.18, reaches
below zero; the figures drew it so (the hardness figure). They now draw the
same interval in log space (logit space for fractions).
"""

import matplotlib
import numpy as np
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from roughcontact.contact.aggregate import statistics  # noqa: E402
from roughcontact.reports.plotting import (  # noqa: E402
    fraction_band,
    plot_band,
    positive_band,
)

#: k_P of 4 surfaces [Pa] with a large scatter (one surface far stiffer).
SAMPLES = np.array([[2e6], [3e6], [4e6], [40e6]])


def cell_rows(samples, quantity="normalized_stiffness"):
    """One cell's rows of an aggregate table at one level, from per-surface samples."""
    mean, half_width, count = statistics(samples)
    return pd.DataFrame({"nominal_pressure": [1e6], f"{quantity}_mean": mean,
                         f"{quantity}_half_width": half_width, f"{quantity}_count": count,
                         "surfaces": [samples.shape[0]]})


def band_extent(ax):
    """Lowest and highest y of the band drawn on ``ax`` (its fill)."""
    (fill,) = ax.collections
    ys = np.concatenate([path.vertices[:, 1] for path in fill.get_paths()])
    return ys.min(), ys.max()


def test_the_tables_band_of_four_scattered_surfaces_reaches_below_zero():
    mean, half_width, count = statistics(SAMPLES)
    assert count[0] == 4 and mean[0] - half_width[0] < 0  # the case of the issue


def test_a_positive_quantity_is_drawn_with_a_band_above_zero():
    frame = cell_rows(SAMPLES)
    fig, ax = plt.subplots()
    plot_band(ax, frame, "normalized_stiffness", y_scale=1e-6)
    low, high = band_extent(ax)
    mean = frame["normalized_stiffness_mean"].iloc[0] * 1e-6
    ratio = frame["normalized_stiffness_half_width"].iloc[0] / \
        frame["normalized_stiffness_mean"].iloc[0]
    assert low > 0
    assert low == pytest.approx(mean * np.exp(-ratio)) and high == pytest.approx(
        mean * np.exp(ratio))
    plt.close(fig)


def test_a_narrow_band_is_the_tables_interval_to_first_order():
    low, high = positive_band([100.0], [1.0])
    assert low[0] == pytest.approx(99.0, abs=0.01) and high[0] == pytest.approx(101.0, abs=0.01)
    low, high = fraction_band([0.3], [0.003])
    assert low[0] == pytest.approx(0.297, abs=1e-4) and high[0] == pytest.approx(0.303, abs=1e-4)


def test_fractions_stay_within_zero_and_one_and_zero_means_have_no_band():
    samples = np.array([[0.01], [0.02], [0.9], [0.95]])  # shares of 4 surfaces
    mean, half_width, _ = statistics(samples)
    assert mean[0] - half_width[0] < 0 < 1 < mean[0] + half_width[0]
    low, high = fraction_band(mean, half_width)
    assert 0 < low[0] < mean[0] < high[0] < 1
    fig, ax = plt.subplots()
    plot_band(ax, cell_rows(samples, "real_area_fraction"), "real_area_fraction", y_scale=100.0)
    low, high = band_extent(ax)
    assert 0 < low and high < 100
    plt.close(fig)
    assert positive_band([0.0], [0.0]) == ([0.0], [0.0])
    assert fraction_band([0.0, 1.0], [0.0, 0.0])[1].tolist() == [0.0, 1.0]
    # one surface: no half width, no band
    assert positive_band([5.0], [np.nan]) == ([5.0], [5.0])

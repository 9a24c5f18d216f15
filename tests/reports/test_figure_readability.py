"""Figures: bands of positive quantities stay positive, log tick labels stay apart.

With 4 surfaces per cell (the quick study) and a large scatter, the
Student-t band of the tables, mean +- t s / sqrt(n) with t = 3.18, reaches
below zero; the figures drew it so (the hardness figure). They now draw the
same interval in log space (logit space for fractions). On the narrow panels
of the measured figure, a log axis spanning about a decade (pressures of a
few kPa to a few tenths of a MPa) labelled its minor ticks so that they ran
into each other; save_figure now keeps them apart. (Typeset symbols:
tests/reports/test_convergence.py.)
"""

import matplotlib
import numpy as np
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from roughcontact.contact.aggregate import statistics  # noqa: E402
from roughcontact.reports.plotting import (  # noqa: E402
    drawn_tick_labels,
    fraction_band,
    overlapping_labels,
    plot_band,
    positive_band,
    save_figure,
    tidy_log_ticks,
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
    # a half width 1e3 times its mean (most surfaces sealed): finite, e^50 either way
    low, high = positive_band([1e-16], [1e-13])
    assert np.isfinite(high).all() and low[0] > 0.0
    np.testing.assert_allclose([low[0], high[0]], [1e-16 * np.exp(-50), 1e-16 * np.exp(50)])


def measured_layout(low: float, high: float):
    """The measured figure's grid (four panels above, three below, 16 x 7.6 in), log x
    axes over ``low`` .. ``high``, and the spectrum panel log-log."""
    fig = plt.figure(figsize=(16, 7.6))
    grid = fig.add_gridspec(2, 12)
    top = [fig.add_subplot(grid[0, 3 * k:3 * k + 3]) for k in range(4)]
    bottom = [fig.add_subplot(grid[1, 4 * k:4 * k + 4]) for k in range(3)]
    x = np.geomspace(low, high, 12)
    for ax in bottom:
        ax.plot(x, x)
        ax.set(xscale="log", xlabel="nominal pressure $P$ [MPa]")
    top[3].loglog(x, np.geomspace(2e-20, 5e-20, 12))
    fig.tight_layout()
    return fig


def log_axes(fig):
    return [axis for ax in fig.axes for axis in (ax.xaxis, ax.yaxis) if axis.get_scale() == "log"]


@pytest.mark.parametrize(("low", "high"), [(5e-5, 5e-4), (0.1, 0.5), (0.2, 0.9), (1.0, 50.0)])
def test_log_tick_labels_are_kept_apart_and_still_read(low, high):
    fig = measured_layout(low, high)
    crowded = overlapping_labels(fig)
    if (low, high) == (5e-5, 5e-4):
        assert crowded  # the case of the issue: minor labels run into each other
    tidy_log_ticks(fig)
    assert overlapping_labels(fig) == []
    renderer = fig.canvas.get_renderer()
    for axis in log_axes(fig):  # every log axis still reads: two labels at least
        assert len(drawn_tick_labels(axis, renderer)) >= 2
    plt.close(fig)


def test_save_figure_keeps_the_labels_apart(tmp_path):
    fig = measured_layout(5e-5, 5e-4)
    save_figure(fig, tmp_path / "figure.png")
    assert (tmp_path / "figure.png").stat().st_size > 0
    assert overlapping_labels(fig) == []
    plt.close(fig)

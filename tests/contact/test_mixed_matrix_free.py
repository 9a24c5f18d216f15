"""precision="mixed" with a grid FFT operator: CG's search products in float32, result exact."""

import numpy as np

from roughcontact import contact
from roughcontact.contact import SolverOptions
from roughcontact.contact.checks import as_operator
from roughcontact.contact.products import Products
from roughcontact.elasticity.halfspace import SpectralHalfSpace


def test_cg_takes_float32_fft_products_and_still_meets_tol():
    op = SpectralHalfSpace((32, 24), (1.2e-3, 1e-3), 1e9, 0.3)
    products = Products.of(as_operator(op), "mixed")
    assert products.mixed
    rows = np.random.default_rng(0).random((2, 32 * 24))
    exact = products.exact(rows)
    assert np.abs(products.search(rows) - exact).max() <= 2e-6 * np.abs(exact).max()
    assert not Products.of(as_operator(op), "double").mixed
    rng = np.random.default_rng(1)
    z = rng.standard_normal((24, 32)) * 1e-6
    gap = z.max() - z
    d = 0.4 * gap.mean()
    mixed = contact.solve(op, gap, d,
                          options=SolverOptions(method="cg", tol=1e-11, precision="mixed"))
    double = contact.solve(op, gap, d,
                           options=SolverOptions(method="cg", tol=1e-11, precision="double"))
    assert mixed.converged and contact.kkt_residual(op, gap, d, mixed.pressure) <= 1e-11
    np.testing.assert_array_equal(mixed.contact_set, double.contact_set)
    assert np.abs(mixed.pressure - double.pressure).max() <= 1e-8 * double.max_pressure

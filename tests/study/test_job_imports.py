"""Every workflow job is a new Python process, so what its modules import at the top
is paid once per job (71 jobs in the default study). The job bodies import the heavy
libraries they need where they use them: a contact job on a dense matrix loads no
table, statistics, FFT, signal or schema library, and the figure notebooks' plotting
module no numerical one. Checked in a fresh interpreter (this one has them all)."""

import subprocess
import sys

import pytest

#: Modules that cost 0.05-0.5 s each to import and that the job modules below never
#: need at import time.
HEAVY = ("pandas", "scipy.stats", "scipy.signal", "scipy.fft", "scipy.optimize",
         "scipy.interpolate", "scipy.ndimage", "jsonschema", "snakemake", "matplotlib")


def loaded_after(module: str) -> list[str]:
    code = (f"import sys, {module}\n"
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    return proc.stdout.split()


@pytest.mark.parametrize("module", ["roughcontact.study.jobs.influence",
                                    "roughcontact.study.jobs.surfaces",
                                    "roughcontact.study.jobs.contact",
                                    "roughcontact.study.contact_jobs",
                                    "roughcontact.study.surface_jobs",
                                    "roughcontact.contact",
                                    "roughcontact.reports.plotting",
                                    "roughcontact.reports.study_figures",
                                    "roughcontact.reports.execution"])
def test_job_modules_import_no_heavy_library(module):
    assert loaded_after(module) == []


def test_the_aggregation_job_loads_pandas_but_no_statistics_library():
    # the 95 % bands take the Student-t quantile from scipy.special (stdtrit)
    assert loaded_after("roughcontact.study.jobs.aggregation") == ["pandas"]


def test_the_lazy_imports_give_the_same_numbers():
    """scipy.special.stdtrit and ndtri are what scipy.stats' t.ppf and norm.isf call."""
    import numpy as np
    import scipy.special
    import scipy.stats

    from roughcontact.contact.aggregate import statistics
    from roughcontact.surfaces import johnson

    df = np.arange(1, 400)
    for q in (0.975, 0.995, 0.9):
        np.testing.assert_array_equal(scipy.special.stdtrit(df, q), scipy.stats.t.ppf(q, df))
    samples = np.random.default_rng(0).standard_normal((7, 5))
    samples[:4, 1] = np.nan
    mean, half, count = statistics(samples, 0.95)
    np.testing.assert_array_equal(count, [7, 3, 7, 7, 7])
    t = scipy.stats.t.ppf(0.975, count - 1)
    np.testing.assert_allclose(half, t * np.nanstd(samples, axis=0, ddof=1) / np.sqrt(count),
                               rtol=1e-13)
    curve = johnson.fit(0.5, 1.25)  # on the ST line: a two-point law
    eta = np.linspace(-3.0, 3.0, 61)
    expected = np.where(eta > scipy.stats.norm.isf(curve.delta), curve.lam, curve.xi)
    assert curve.family == "ST"
    np.testing.assert_array_equal(curve.transform(eta), expected)


def test_the_file_readers_load_neither_the_solvers_nor_the_finite_element_model():
    """A figure or job that reads stored files only (surfaces, tables) does not load the
    contact solvers or scikit-fem through the readers."""
    code = ("import sys, roughcontact.study.jobs.storage\n"
            "print(' '.join(m for m in ('roughcontact.contact', 'roughcontact.elasticity',"
            " 'skfem', 'scipy.sparse', 'scipy.linalg') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert proc.stdout.split() == []

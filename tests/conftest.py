"""Test-session settings shared by every test directory.

``make test`` runs the files on both cores, one file per worker at a time
(pytest-xdist ``--dist loadfile``), in collection order. The files that run
whole studies take 1-4 minutes each; collected last (``tests/workflow`` sorts
last), they left one worker idle for minutes at the end. They are collected
first, longest first, so that the short files fill in around them.
"""

#: Files of more than about a minute (measured 2026-11-26 on 2 cores), longest first.
LONG_FILES = (
    "tests/workflow/test_workflow.py",  # the quick study's fixture (128 s) and its reports
    "tests/surfaces/test_synthetic.py",
    "tests/hard/test_synthetic_memory.py",
    "tests/workflow/test_stored_results.py",
    "tests/workflow/test_operator_workflow.py",
    "tests/workflow/test_cluster.py",
    "tests/workflow/test_stored_parameters.py",
    "tests/surfaces/test_spectra.py",
)


def pytest_collection_modifyitems(config, items):
    """Move the tests of :data:`LONG_FILES` to the front, in that order (stable: the
    order within a file, and of the other files, is kept)."""
    rank = {path: k for k, path in enumerate(LONG_FILES)}

    def key(item):
        path = item.nodeid.split("::", 1)[0]
        return rank.get(path, len(rank))

    items.sort(key=key)

import os
import sys
from pathlib import Path

# tests/chain_plant.py is a test helper module, imported by name.
sys.path.insert(0, str(Path(__file__).resolve().parent))


import pytest  # noqa: E402

# pytester runs small test files in a subprocess-free sandbox (tests/test_ci_strict.py).
pytest_plugins = ["pytester"]


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """In CI (``CI`` set, as ``.ci/run`` does), a skipped test is a failure: a test that
    cannot run there (no Chromium, no offline build backend) must not pass silently."""
    outcome = yield
    report = outcome.get_result()
    if os.environ.get("CI") and report.skipped and not hasattr(report, "wasxfail"):
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else report.longrepr
        report.outcome = "failed"
        report.longrepr = f"skipped in CI (CI is set), which counts as a failure: {reason}"


#: Session fixtures too costly to build once per worker under pytest-xdist (``-n auto``): the
#: tests that use one run on one worker (``--dist loadgroup``, the README's test command), so
#: each is built once per session as without xdist.
SHARED_SESSION_FIXTURES = ("full_paper",)


def pytest_collection_modifyitems(config, items):
    for item in items:
        for name in SHARED_SESSION_FIXTURES:
            if name in getattr(item, "fixturenames", ()):
                item.add_marker(pytest.mark.xdist_group(name))


@pytest.fixture(scope="session")
def full_paper(tmp_path_factory):
    """`aerial-drake run paper` in full (nominal and disturbed, 15 s each), run once per test
    session: the paper's claims are tested on it in tests/studies/test_paper.py and
    tests/simulation/test_closed_loop.py."""
    from aerial_drake.studies.paper import run_paper

    out = tmp_path_factory.mktemp("paper")
    result = run_paper(out, progress=False)
    assert result.completed, result.failures
    return result

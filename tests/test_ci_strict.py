"""In CI a skip is a failure, and an empty parametrization never passes as one skipped test."""

from pathlib import Path

CONFTEST = (Path(__file__).parent / "conftest.py").read_text()


def _run(pytester, monkeypatch, ci: str | None, body: str):
    if ci is None:
        monkeypatch.delenv("CI", raising=False)
    else:
        monkeypatch.setenv("CI", ci)
    pytester.makeconftest(CONFTEST)
    pytester.makeini("[pytest]\nempty_parameter_set_mark = fail_at_collect\n")
    pytester.makepyfile(test_sample=body)
    return pytester.runpytest()


SKIPPING = """
import pytest

def test_needs_a_browser():
    pytest.skip("Chromium is not installed")

@pytest.mark.skipif(True, reason="no offline build backend")
def test_marked():
    pass
"""


def test_skip_is_a_failure_in_ci(pytester, monkeypatch):
    result = _run(pytester, monkeypatch, "true", SKIPPING)
    # The call-time skip fails its test; the marker's skip fails at setup (reported as an error).
    result.assert_outcomes(failed=1, errors=1)
    result.stdout.fnmatch_lines(["*skipped in CI*Chromium is not installed*"])


def test_skip_stays_a_skip_outside_ci(pytester, monkeypatch):
    result = _run(pytester, monkeypatch, None, SKIPPING)
    result.assert_outcomes(skipped=2)


def test_empty_parametrization_is_an_error(pytester, monkeypatch):
    body = "import pytest\n\n@pytest.mark.parametrize('name', [])\ndef test_each(name):\n    pass\n"
    result = _run(pytester, monkeypatch, None, body)
    result.assert_outcomes(errors=1)

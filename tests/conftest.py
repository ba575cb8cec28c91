import sys
from pathlib import Path

# tests/chain_plant.py is a test helper module, imported by name.
sys.path.insert(0, str(Path(__file__).resolve().parent))


import pytest  # noqa: E402


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

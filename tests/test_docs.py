"""The documentation cites only what the package ships, says how to run the notebooks, and
dates the wall times it quotes with the script that measured them."""

import re
import subprocess
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]


def tracked_text_files() -> list[Path]:
    names = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                           check=True).stdout.split()
    suffixes = {".py", ".md", ".ipynb", ".yaml", ".rst", ".toml", ".txt"}
    return [ROOT / n for n in names if Path(n).suffix in suffixes and (ROOT / n).is_file()]


def test_no_reference_to_documents_the_package_does_not_ship():
    """"design note N" pointed at notes outside the repository: cite docs/ or the paper."""
    pattern = re.compile("design" + r"[ -]notes?\b", re.IGNORECASE)
    offenders = [str(p.relative_to(ROOT)) for p in tracked_text_files()
                 if p.name != Path(__file__).name and pattern.search(p.read_text())]
    assert not offenders


def test_the_notebooks_extra_and_the_readme_line_that_uses_it():
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]
    assert {"jupyter", "ipykernel", "nbclient", "nbformat"} <= set(extras["notebooks"])
    assert extras["docs"] == ["sphinx"]
    readme = (ROOT / "README.md").read_text()
    assert 'pip install -e ".[notebooks]"' in readme and "notebooks/" in readme
    assert "docs/api" in readme


def test_quoted_wall_times_name_their_script_and_date():
    for page in ("README.md", "docs/paper.md", "docs/analysis.md"):
        text = (ROOT / page).read_text()
        assert "tools/docs_timings.py" in text, page
        assert re.search(r"20\d\d-\d\d-\d\d", text), page
    assert (ROOT / "tools" / "docs_timings.py").is_file()

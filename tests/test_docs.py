"""The README, the docs, the package and its tests describe the toolkit as it
is, not how it came to be (CHANGELOG.md is where that goes); the README
stays short and every page it links to exists."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: words of a development log: its stops and issues, and what was not done
HISTORY = re.compile(r"\b(this|last|earlier|previous) stop\b|\bissue #?\d+|\bnot adopted\b|"
                     r"\blanded\b|\bthe code before\b", re.IGNORECASE)
#: a relative link in markdown: [text](target)
LINK = re.compile(r"\]\((?!https?:|#)([^)#\s]+)")


def scanned() -> list[Path]:
    """README, docs, every Python file of the package, its tests, examples
    and benchmarks (this one aside: it names the words) and every YAML file
    of theirs and of the models and problems."""
    files = [ROOT / "README.md", *(ROOT / "docs").rglob("*.md"),
             *(path for folder in ("design", "tests", "examples", "benchmarks", "models",
                                   "problems")
               for pattern in ("*.py", "*.yaml") for path in (ROOT / folder).rglob(pattern))]
    return [f for f in files if f != Path(__file__).resolve()]


def test_nothing_speaks_of_development_history():
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}" for path in scanned()
             for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
             if HISTORY.search(line)]
    assert found == []


def test_the_history_words_are_caught():
    for line in ("measured this stop", "at the last stop", "(issue 12, item 8)",
                 "Issue #4's targets", "tried, not adopted", "the last landed stop's run",
                 "the code before"):
        assert HISTORY.search(line), line
    for line in ("the belt stops", "a non-issue", "the bird lands", "stop at 0.5 s"):
        assert not HISTORY.search(line), line


def test_the_readme_is_short_and_its_links_resolve():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= 250
    for page in [ROOT / "README.md", *(ROOT / "docs").glob("*.md")]:
        for target in LINK.findall(page.read_text(encoding="utf-8")):
            assert (page.parent / target).exists(), f"{page.name}: {target}"


def test_the_measured_pages_are_made_from_the_results():
    """docs/performance.md has a section, with machine and date, for every
    benchmark result it knows; the reproduction's summary counts what its
    result counts."""
    import json

    from benchmarks import pages

    page = pages.performance_page()
    known = [name for name in pages.PAGES if (pages.RESULTS / name).exists()]
    for name in known:
        assert f"(`benchmarks/results/{name}`), measured " in page, name
    data = json.loads(pages.REPRODUCTION.read_text())
    summary = pages.reproduction_summary()
    assert f"{data['agree']} of {data['total']} counted rows agree" in summary
    assert pages.BEGIN in (ROOT / "docs" / "validation.md").read_text(encoding="utf-8")

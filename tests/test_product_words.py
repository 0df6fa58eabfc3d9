"""The product speaks of itself alone: no word of how it was built (a session or issue number, an
engineer's letter, a coordination file) in the code, tests, configs, workflow, docs or README. Such a
sentence means nothing to a user and turns false at the next change; the history belongs in
CHANGELOG.md, which is the one file excepted."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TREES = ("src", "tests", "config", "workflow", "docs", "README.md")
EXCEPTED = {"CHANGELOG.md"}
WORDS = re.compile(r"sessions? [0-9]|issues? [0-9]|engineer [A-Z]\b|common\.md|\bthe lead\b", re.IGNORECASE)
SKIP_DIRS = {"__pycache__", ".pytest_cache", ".ipynb_checkpoints"}


def _files(root: Path):
    for tree in TREES:
        top = root / tree
        if top.is_file():
            yield top
            continue
        for f in sorted(top.rglob("*")) if top.is_dir() else ():
            rel = f.relative_to(root).parts
            if f.is_file() and not SKIP_DIRS.intersection(rel) and not any(p.endswith(".egg-info") for p in rel) \
                    and f.name not in EXCEPTED:
                yield f


def offenders(root: Path = ROOT) -> list[str]:
    """``path:line: text`` of every line that names how the product was built (text files only)."""
    out = []
    for f in _files(root):
        try:
            text = f.read_text(encoding="utf-8")
        except (UnicodeDecodeError, OSError):
            continue  # binary (figures, numba caches)
        for n, line in enumerate(text.splitlines(), 1):
            if WORDS.search(line):
                out.append(f"{f.relative_to(root)}:{n}: {line.strip()[:160]}")
    return out


def test_no_word_of_how_the_product_was_built():
    found = offenders()
    assert not found, f"{len(found)} line(s) name sessions, issues or engineers:\n" + "\n".join(found)


# the planted words are assembled at run time so that this file does not match its own pattern
@pytest.mark.parametrize("planted", ["# since Sess" + "ion 12 the default", "see iss" + "ue 25, item 1",
                                     "engin" + "eer C's stage", "as comm" + "on.md says"])
def test_a_planted_word_is_caught(tmp_path, planted):
    for tree in ("src/pkg", "docs", "tests"):
        (tmp_path / tree).mkdir(parents=True)
    (tmp_path / "README.md").write_text("# clean\n\nThe default is the no-slip bed.\n")
    (tmp_path / "docs" / "model.md").write_text("A paragraph about issues of resolution, a session-free text.\n")
    (tmp_path / "CHANGELOG.md").write_text(f"- {planted}\n")  # the changelog is excepted
    assert offenders(tmp_path) == []
    (tmp_path / "src" / "pkg" / "mod.py").write_text(f'"""Doc."""\nX = 1  {planted}\n')
    found = offenders(tmp_path)
    assert found == [f"src/pkg/mod.py:2: X = 1  {planted}"]


def test_the_words_are_matched_as_the_brief_gives_them():
    assert WORDS.search("Iss" + "ue 7") and WORDS.search("SESS" + "ION 3") and WORDS.search("engin" + "eer B")
    assert not WORDS.search("engineers at scale") and not WORDS.search("an issue of scale")
    assert not WORDS.search("sessions of the workflow") and not WORDS.search("engineer-scale runs")
    assert WORDS.search("sess" + "ions 1-6") and WORDS.search("the le" + "ad's ladder")
    assert not WORDS.search("the leading edge") and not WORDS.search("lead time")

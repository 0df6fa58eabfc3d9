"""The product speaks of itself alone: no word of how it was built (a session or issue number, a
work-item number, an engineer's letter, a coordination file, the clock time of a run) in any text
file of the repository: code, tests, configs, workflow, profiles, CI, benchmarks, docs, README. Such
a sentence means nothing to a user and turns false at the next change; the history belongs in
CHANGELOG.md, which is the one file excepted."""
from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# scanned where the root is not a git work tree (the tmp_path tests); in a work tree every file git
# knows of (tracked, or new and not ignored) is scanned
TREES = ("src", "tests", "config", "workflow", "profiles", ".ci", "benchmarks", "docs",
         "Snakefile", "README.md", "pyproject.toml")
EXCEPTED = {"CHANGELOG.md"}
_HOUR = r"(?:[01]?\d|2[0-3]):[0-5]\d"
WORDS = re.compile("|".join((
    r"\bsessions?[-\s]?#?\d",      # a session number, spaced, hyphenated or joined
    r"\bissues?[-\s]?#?\d",        # an issue number (a bare #N is left alone: too common a form)
    r"\bitems?[-\s]#?\d",          # a work-item number
    r"\b(?:this|that|previous|last|next|earlier|prior) (?:issue|session)s?\b",
    r"\bengineer[-\s](?-i:[A-Z])\b",  # an engineer's letter (a capital)
    r"common\.md",
    r"\bthe lead\b",
    _HOUR + r"\s?(?:UTC|GMT|h\b)",  # the clock time of a day: with its zone ...
    r"\bat " + _HOUR + r"\b(?!:\d)",  # ... or after "at" (not a duration h:mm:ss)
)), re.IGNORECASE)
SKIP_DIRS = {"__pycache__", ".pytest_cache", ".ipynb_checkpoints"}


def _git_files(root: Path) -> list[Path] | None:
    """The files git knows of under ``root`` (tracked, or untracked and not ignored); None where
    ``root`` is not the top of a git work tree or git is missing."""
    if not (root / ".git").exists() or shutil.which("git") is None:
        return None
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                             cwd=root, capture_output=True, check=True).stdout
    except (subprocess.CalledProcessError, OSError):
        return None
    return [root / p for p in sorted(set(out.decode("utf-8", "surrogateescape").split("\0"))) if p]


def _tree_files(root: Path):
    for tree in TREES:
        top = root / tree
        if top.is_file():
            yield top
            continue
        yield from (sorted(top.rglob("*")) if top.is_dir() else ())


def _files(root: Path):
    listed = _git_files(root)
    for f in (listed if listed is not None else _tree_files(root)):
        rel = f.relative_to(root).parts
        if f.is_file() and not SKIP_DIRS.intersection(rel) and not any(p.endswith(".egg-info") for p in rel) \
                and f.name not in EXCEPTED:
            yield f


def _text(f: Path) -> str | None:
    """The file's text, or None for a binary file (figures, NetCDF, numba caches)."""
    try:
        raw = f.read_bytes()
    except OSError:
        return None
    if b"\0" in raw[:8192]:
        return None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return None


def scanned(root: Path = ROOT) -> list[Path]:
    """The text files the guard reads."""
    return [f for f in _files(root) if _text(f) is not None]


def offenders(root: Path = ROOT) -> list[str]:
    """``path:line: text`` of every line that names how the product was built (text files only)."""
    out = []
    for f in _files(root):
        text = _text(f)
        if text is None:
            continue
        for n, line in enumerate(text.splitlines(), 1):
            if WORDS.search(line):
                out.append(f"{f.relative_to(root).as_posix()}:{n}: {line.strip()[:160]}")
    return out


def test_no_word_of_how_the_product_was_built():
    found = offenders()
    assert not found, f"{len(found)} line(s) name sessions, issues or engineers:\n" + "\n".join(found)


def test_the_whole_repository_is_read():
    if _git_files(ROOT) is None:
        pytest.skip("not a git work tree: the tree list is read")
    names = {f.relative_to(ROOT).as_posix() for f in scanned()}
    assert {"README.md", "Snakefile", "pyproject.toml", "tests/test_product_words.py"} <= names
    assert "CHANGELOG.md" not in names
    for top in ("src/", "tests/", "config/", "workflow/", "docs/", "benchmarks/", "profiles/", ".ci/"):
        assert any(n.startswith(top) for n in names), top
    assert not any(n.endswith(".png") for n in names)


# the planted words are assembled at run time so that this file does not match its own pattern
PLANTED = [
    "# since Sess" + "ion 12 the default", "see iss" + "ue 25, it" + "em 1", "engin" + "eer C's stage",
    "as comm" + "on.md says",
    "the sess" + "ion-3 scheme", "sess" + "ion 3", "Sess" + "ion3", "sess" + "ions 1-6",
    "iss" + "ue-25", "iss" + "ue #25", "ISS" + "UE 7",
    "it" + "em 4 of the list", "it" + "em-4", "it" + "ems 5, 8",
    "th" + "is iss" + "ue", "th" + "is sess" + "ion", "the prev" + "ious sess" + "ion",
    "the la" + "st sess" + "ion", "the ne" + "xt sess" + "ion",
    "run of 12:" + "03 UTC", "12:" + "03UTC", "at 14:" + "30", "finished at 9:" + "05.", "07:" + "35 GMT",
    "the le" + "ad's ladder",
]


@pytest.mark.parametrize("planted", PLANTED)
def test_a_planted_word_is_caught(tmp_path, planted):
    for tree in ("src/pkg", "docs", "tests", "benchmarks", "profiles/slurm", ".ci"):
        (tmp_path / tree).mkdir(parents=True)
    (tmp_path / "README.md").write_text("# clean\n\nThe default is the no-slip bed.\n")
    (tmp_path / "docs" / "model.md").write_text("A paragraph about issues of resolution, a session-free text.\n")
    (tmp_path / "CHANGELOG.md").write_text(f"- {planted}\n")  # the changelog is excepted
    assert offenders(tmp_path) == []
    (tmp_path / "src" / "pkg" / "mod.py").write_text(f'"""Doc."""\nX = 1  {planted}\n')
    assert offenders(tmp_path) == [f"src/pkg/mod.py:2: X = 1  {planted}"]
    for where in ("Snakefile", "pyproject.toml", "benchmarks/bench.py", "profiles/slurm/config.yaml", ".ci/run"):
        (tmp_path / where).write_text(f"# {planted}\n")
        assert f"{where}:1: # {planted}" in offenders(tmp_path)


# legitimate text that must not match: slices, ratios, durations, pytest and HTTP sessions, prose
NOT_PLANTED = [
    "a[10:20]", "x = t[1:3]", "ratio 1:2", "1:25 000 map", "elapsed 0:02:33", "took 0:02:33 at 0:02:33",
    "time: 00:30", "a[:, 10:20]", "issues of resolution", "the session-free text", "an issue of scale",
    "0 issues; tests/edges/test_cf.py", "sessions of the workflow", "once per session, in",
    "def pytest_sessionfinish(session, exitstatus):", '@pytest.fixture(scope="session")',
    "for item in session.items:", "s = requests.Session(); s.get(url)", "items[3]", "item_4 = 2",
    "engineers at scale", "engineer-scale runs", "engineer a stage", "the leading edge", "lead time",
    "a posses" + "sion 3 times", "tis" + "sue 3", "#25 in the list", "this issuer", "the last sessionless run",
]


@pytest.mark.parametrize("text", NOT_PLANTED)
def test_legitimate_text_is_not_caught(text):
    assert not WORDS.search(text), WORDS.search(text).group(0)


def test_the_words_are_matched_as_the_brief_gives_them():
    assert WORDS.search("Iss" + "ue 7") and WORDS.search("SESS" + "ION 3") and WORDS.search("engin" + "eer B")
    assert not WORDS.search("engineers at scale") and not WORDS.search("an issue of scale")
    assert not WORDS.search("sessions of the workflow") and not WORDS.search("engineer-scale runs")
    assert WORDS.search("sess" + "ions 1-6") and WORDS.search("the le" + "ad's ladder")
    assert not WORDS.search("the leading edge") and not WORDS.search("lead time")


@pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")
def test_a_git_work_tree_is_read_whole(tmp_path):
    """In a work tree every text file git knows of is read, wherever it lies; ignored, binary and
    the changelog are not."""
    planted = "the ne" + "xt sess" + "ion"
    subprocess.run(["git", "init", "-q", str(tmp_path)], check=True)
    (tmp_path / ".gitignore").write_text("scratch/\n")
    (tmp_path / "scratch").mkdir()
    (tmp_path / "scratch" / "notes.md").write_text(f"{planted}\n")  # ignored
    (tmp_path / "CHANGELOG.md").write_text(f"- {planted}\n")
    (tmp_path / "figure.png").write_bytes(b"\x89PNG\0\0" + planted.encode())
    (tmp_path / "tools").mkdir()
    (tmp_path / "tools" / "helper.sh").write_text(f"echo ok  # {planted}\n")  # outside every tree
    (tmp_path / "requirements.txt").write_text("numpy\n")
    subprocess.run(["git", "add", "tools", "figure.png", "CHANGELOG.md"], cwd=tmp_path, check=True)
    assert offenders(tmp_path) == [f"tools/helper.sh:1: echo ok  # {planted}"]
    assert {f.name for f in scanned(tmp_path)} == {".gitignore", "helper.sh", "requirements.txt"}

"""The README stays a front page: short, the two set-up commands first, the generated status block."""
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"
SETUP = ("python3 -m venv .venv && . .venv/bin/activate && pip install -r requirements-lock.txt && "
         "pip install --no-deps -e . && ")


def test_readme_is_short_and_starts_with_the_two_setup_commands():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 150
    head = lines[:30]
    assert SETUP + "snakemake -j2" in head and SETUP + "pytest" in head


def test_readme_links_every_topic_page():
    text = README.read_text(encoding="utf-8")
    for page in ("docs/usage.md", "docs/model.md", "docs/paper-notes.md", "docs/verification.md",
                 "docs/reproduction.md", "docs/performance.md", "CHANGELOG.md"):
        assert f"]({page})" in text and (README.parent / page).is_file(), page

"""The README's status block is the generator's: a block typed by hand or left by an older generator fails."""
from granudep.report.readme_status import BEGIN, END, status_block


def _labels(block: str) -> list[str]:
    import re
    return [m.group(1) for m in re.finditer(r"^- \*\*([^*]+)\*\*", block, flags=re.M)]


def test_the_project_readme_block_has_the_generators_current_labels(tmp_path):
    """A stale block (typed by hand, or written by an older generator) is caught here: every line the
    generator writes whatever the results (run, verification, chain dx, claims, Tables 3 and 5) is in the
    README's block under the same label."""
    from pathlib import Path
    text = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    readme = _labels(text[text.index(BEGIN):text.index(END)])
    always = [lab for lab in _labels(status_block(tmp_path)) if not lab.startswith(("DA vs", "Variant"))]
    assert {"Last run", "Verification", "Claims scorecard", "Table 3", "Table 5"} <= set(always)
    missing = [lab for lab in always if not any(r.startswith(lab) for r in readme)]
    assert not missing, f"README status block lacks {missing}: run `granudep readme-status README.md`"

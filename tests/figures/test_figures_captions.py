"""Report captions: one per figure name, valid reStructuredText, quoting the paper's numbers."""
from pathlib import Path

import pytest

from granudep.figures import FIGURES

REPORT = Path(__file__).resolve().parents[2] / "workflow" / "report"


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_caption_exists_and_parses(name):
    docutils_core = pytest.importorskip("docutils.core")
    path = REPORT / f"{name}.rst"
    text = path.read_text()
    assert "*Paper:*" in text and "*Ours:*" in text
    errors = []
    docutils_core.publish_doctree(text, settings_overrides={"report_level": 2, "halt_level": 5,
                                                           "warning_stream": _Sink(errors)})
    assert not errors, errors


class _Sink:
    def __init__(self, out):
        self.out = out

    def write(self, s):
        if s.strip():
            self.out.append(s)


@pytest.mark.parametrize("name,numbers", [("fig5", ["55.8°", "57.75°", "0.78 s"]), ("fig7", ["8.5", "13.5"]),
                                          ("fig16", ["55 %", "107 %", "17 %", "69 %"]), ("fig9", ["3.67", "6.89"])])
def test_caption_quotes_paper(name, numbers):
    text = (REPORT / f"{name}.rst").read_text()
    for n in numbers:
        assert n in text

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


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_caption_quotes_our_number_and_renders_clean(name):
    """Every caption's 'Ours' line takes a number from the outputs (config['_caption_numbers'])
    and the rendered text is still clean reStructuredText."""
    jinja2 = pytest.importorskip("jinja2")
    docutils_core = pytest.importorskip("docutils.core")
    from types import SimpleNamespace
    text = (REPORT / f"{name}.rst").read_text()
    ours = text.split("*Ours:*", 1)[1]
    assert '_caption_numbers' in ours
    keys = __import__("re").findall(r'get\("([A-Za-z0-9]+)", "not computed yet"\)', ours)
    assert keys
    nums = {k: f"planted number {k} = 1.23 (dx = 4 mm)" for k in keys}
    rendered = jinja2.Environment().from_string(text).render(snakemake=SimpleNamespace(config={"_caption_numbers": nums}))
    for k in keys:
        assert nums[k] in rendered
    errors = []
    docutils_core.publish_doctree(rendered, settings_overrides={"report_level": 2, "halt_level": 5,
                                                               "warning_stream": _Sink(errors)})
    assert not errors, errors

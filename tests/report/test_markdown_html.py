"""granudep.report.markdown_html: the summary rendered for the Snakemake report."""
from __future__ import annotations

from granudep.report.markdown_html import inline, to_html

MD = """# Title

Intro with `results/x.csv` and **bold** and _italic_; t_s and (hu)_C stay as written; a < b.

## Table 3

| case | t_s | note |
|---|---|---|
| T22-A70 | 7.9 | `a|b` ok |
| T16-A50 | 6.1 | x \\| y |

- one
- two
  continued

```
raw *not* markup
```
"""


def test_headings_tables_lists_code():
    h = to_html(MD)
    assert h.startswith("<!DOCTYPE html>") and "<h1>Title</h1>" in h and "<h2>Table 3</h2>" in h
    assert "<thead><tr><th>case</th><th>t_s</th><th>note</th></tr></thead>" in h
    assert h.count("<tr>") == 3 and "<td>T16-A50</td>" in h and "<td>x | y</td>" in h
    assert "<ul><li>one</li><li>two continued</li></ul>" in h
    assert "<pre><code>raw *not* markup</code></pre>" in h


def test_inline_markup_escapes_and_keeps_subscripts():
    s = inline("**b** _i_ t_s (hu)_C `<x>` a < b")
    assert "<strong>b</strong>" in s and "<em>i</em>" in s
    assert "t_s" in s and "(hu)_C" in s and "<code>&lt;x&gt;</code>" in s and "a &lt; b" in s

"""The report stage: what the paper's comparison and our summary are made of, read from the outputs.

One module per thing it makes:

* :mod:`.da_vs_reference` -- 2D reference runouts and flow times (``reference_2d.csv``), the DA runs'
  errors against them (``comparison.csv``) and the reading matrix (``granudep reference``, ``compare``)
* :mod:`.claims` -- the claims scorecard (``claims.csv``)
* :mod:`.summary` -- ``summary.md`` (paper-vs-ours tables, verification, benchmarks, figures), with
  :mod:`.studies` (its convergence and sensitivity sections) and :mod:`.markdown` (tables, readers)
* :mod:`.markdown_html` -- the same summary as a standalone HTML page
* :mod:`.captions` -- ``caption_numbers.json``, our number in each report caption
* :mod:`.sensitivity_table` -- ``sensitivity.csv`` of the sensitivity study (``granudep sensitivity-table``)
* :mod:`.readme_status` -- the README's generated status block (``granudep readme-status``)

The paper-vs-ours Tables 3 and 5 are written by the regression stage (``regress/paper_tables.py``).
The report reads the figures' files, never the figure modules (no upward import).
"""

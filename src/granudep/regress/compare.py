"""Old name of :mod:`granudep.regress.paper_tables` (paper-vs-ours Tables 3 and 5).

Kept so that ``from granudep.regress.compare import ...`` keeps working (the same module object).
New code imports ``granudep.regress.paper_tables``.
"""
import sys

from . import paper_tables as _module

sys.modules[__name__] = _module

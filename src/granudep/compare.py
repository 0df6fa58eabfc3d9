"""Old name of :mod:`granudep.report.da_vs_reference` (DA runs vs 2D/measured references, Figs 15–16).

Kept so that ``import granudep.compare`` / ``from granudep.compare import ...`` keep working: this
name is the same module object (monkeypatching either patches both). New code imports
``granudep.report.da_vs_reference``.
"""
import sys

from .report import da_vs_reference as _module

sys.modules[__name__] = _module

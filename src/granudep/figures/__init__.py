"""Figures of the paper, one plotting function per figure, each drawn from the stage outputs.

Every function takes datasets/tables (or paths to them) and returns a matplotlib ``Figure``
(object-oriented API, no pyplot state, Agg-safe); ``granudep figure NAME -o OUT.png INPUTS...``
draws it and writes it atomically with :func:`granudep.io.save_figure`.

Modules: :mod:`.runout` (Figs 15, 16, 17: DA vs reference), :mod:`.isph2d` (Figs 5, 7/A3, 10:
2D particle runs), :mod:`.fig6` (Fig 6: F/D interface of the a = 7 quartz column on a
horizontal plane), :mod:`.sections` (Figs 8, 9, 11, A1, A2: monitoring sections),
:mod:`.regression` (Figs 12, 13: critical momentum and A, B), :mod:`.studies` (convergence,
sensitivity). :data:`FIGURES` maps each CLI name to its :class:`~.common.FigureSpec`.
"""
from __future__ import annotations

from .common import REGISTRY as FIGURES  # noqa: F401  (filled by the imports below)
from . import runout, isph2d, fig6, sections, regression, studies  # noqa: F401,E402

__all__ = ["FIGURES"]

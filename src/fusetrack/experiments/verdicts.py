"""Every paper's central contributions (``experiments/PAPER/verdict.py``), in one list."""

from __future__ import annotations

import importlib

from ..evaluation import PaperVerdict

PAPERS = ("lee2009", "zhai2007", "ercan2013", "kushwaha2010", "nott2009")


def paper_verdicts() -> list[PaperVerdict]:
    """The :class:`PaperVerdict` of each paper of :data:`PAPERS`, in that order."""
    return [importlib.import_module(f"{__package__}.{p}.verdict").VERDICT for p in PAPERS]

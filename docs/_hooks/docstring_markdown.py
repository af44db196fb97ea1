"""A griffe extension (``mkdocs.yml``: mkdocstrings ``extensions``) for docstrings written in the
reStructuredText habits of the code: doctest examples at the left margin of a docstring
(``>>> w.accept(5)`` then its output) become fenced ``pycon`` blocks, so Markdown shows them as
code instead of reading ``[a]\\n[b]`` output as a link; Sphinx roles (``:class:`X```) become
code spans, and a paragraph's closing ``::`` a colon."""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:class|func|meth|mod|attr|data|obj|exc|const):`~?\.?([^`]+)`")


def fence_doctests(text: str) -> str:
    """Wrap every run of left-margin ``>>>`` lines and their output (up to a blank line)."""
    out: list[str] = []
    in_example = in_fence = False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            in_fence = not in_fence
        if not in_fence and not in_example and line.startswith(">>>"):
            if out and out[-1].strip():
                out.append("")
            out.append("```pycon")
            in_example = True
        elif in_example and not line.strip():
            out.append("```")
            in_example = False
        out.append(line)
    if in_example:
        out.append("```")
    return "\n".join(out)


def rst_habits(text: str) -> str:
    """Sphinx roles as code spans; ``Example::`` (a literal block follows) as ``Example:``."""
    text = ROLE.sub(r"`\1`", text)
    return re.sub(r"(\S)::$", r"\1:", text, flags=re.M)


class DocstringMarkdown(griffe.Extension):
    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = rst_habits(fence_doctests(obj.docstring.value))

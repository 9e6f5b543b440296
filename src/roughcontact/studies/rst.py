"""reStructuredText building blocks of the report's fragments: literals, tables, headings, folds."""

from __future__ import annotations

import json
from collections.abc import Sequence


def literal(value) -> str:
    """A value as RST inline literal text: strings bare, lists of strings joined, the rest JSON; text that a
    literal cannot hold (backquotes, backslashes, edge spaces, newlines) escaped instead."""
    if isinstance(value, str):
        text = value
    elif isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
        text = ", ".join(value)
    else:
        text = json.dumps(value, sort_keys=True, separators=(", ", ": "))
    if not text:
        return "(empty)"
    if "`" in text or "\\" in text or text != text.strip() or "\n" in text:  # not as a literal: escaped text
        return "".join(c if c.isalnum() else " " if c.isspace() else "\\" + c for c in text)
    return f"``{text}``"


def list_table(header: Sequence[str], rows: Sequence[Sequence[str]], *, widths: str = "auto") -> str:
    """An RST ``list-table`` with one header row; cells are RST text (one line each)."""
    lines = [".. list-table::", "   :header-rows: 1", f"   :widths: {widths}", ""]
    for row in [header, *rows]:
        if len(row) != len(header):
            raise ValueError(f"row {row!r} has {len(row)} cells, the header {len(header)}")
        for i, cell in enumerate(row):
            if "\n" in cell:
                raise ValueError(f"table cell {cell!r} spans lines")
            marker = "* -" if i == 0 else "  -"
            lines.append(f"   {marker} {cell}".rstrip())
    return "\n".join(lines) + "\n"


def heading(title: str, underline: str = "-") -> str:
    """A section title underlined with ``underline``."""
    return f"{title}\n{underline * len(title)}\n"



def folded(summary: str, rst: str) -> str:
    """``rst`` inside an HTML ``<details>`` element, closed, opened by clicking ``summary`` (plain text)."""
    if "<" in summary or "\n" in summary:
        raise ValueError(f"a fold's summary is one line of plain text, got {summary!r}")
    return (f"\n.. raw:: html\n\n   <details><summary>{summary}</summary>\n\n{rst}\n"
            ".. raw:: html\n\n   </details>\n")

"""What the study scripts share: Markdown tables and their place in a docs/ page.

A study script prints its table and writes it between two markers of its page
(``<!-- name:start -->`` ... ``<!-- name:end -->``), so the prose around it stays as written.
"""

from __future__ import annotations

from pathlib import Path


def markdown_table(head, rows) -> str:
    """A Markdown table: ``head`` the column titles, ``rows`` sequences of cells."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def put_between(doc: str, markers: tuple[str, str], text: str) -> str:
    """``doc`` with ``text`` in place of what stands between ``markers``; a page without
    them is an error naming the marker."""
    start, end = markers
    for m in markers:
        if m not in doc:
            raise ValueError(f"marker {m!r} not found in the page")
    i, j = doc.index(start) + len(start), doc.index(end)
    return doc[:i] + "\n" + text.rstrip("\n") + "\n" + doc[j:]


def write_between(page: Path, markers: tuple[str, str], text: str) -> None:
    """Write ``text`` between ``markers`` of the page file ``page``."""
    page.write_text(put_between(page.read_text(), markers, text))

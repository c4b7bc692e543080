"""Self-contained HTML reports: tables and matplotlib figures embedded as base64 PNG data URIs.

Shared by ``s2r calibrate --report`` and ``s2r validate --report``. Uses matplotlib's Agg backend only.
"""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from s2r.fileio import atomic_write_text

__all__ = ["ReportSection", "figure_to_data_uri", "html_table", "image_to_data_uri", "render_report", "write_report"]

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { border-bottom: 2px solid #444; } h2 { margin-top: 2em; border-bottom: 1px solid #bbb; }
table { border-collapse: collapse; margin: 0.5em 0; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: right; }
th { background: #f0f0f0; } td:first-child, th:first-child { text-align: left; }
.fail { background: #fdd; } .pass { background: #dfd; } .warn { background: #ffe9b3; }
img { max-width: 100%; border: 1px solid #ddd; margin: 4px 0; }
.note { color: #555; font-size: 0.9em; }
caption { caption-side: top; text-align: left; font-weight: 600; padding: 4px 0; }
pre { white-space: pre-wrap; overflow-wrap: anywhere; background: #f6f6f6; padding: 8px; font-size: 0.85em; }
.banner { padding: 0.8em 1.2em; border-radius: 6px; font-size: 1.25em; font-weight: 600; margin: 1em 0; }
.banner.pass { background: #2e7d32; color: #fff; } .banner.fail { background: #c62828; color: #fff; }
.banner.warn { background: #f9a825; color: #222; }
.banner small { display: block; font-size: 0.7em; font-weight: 400; margin-top: 0.3em; }
details > summary { cursor: pointer; font-size: 1.5em; font-weight: bold; margin-top: 1.5em;
  border-bottom: 1px solid #bbb; }
td.text, th.text { text-align: left; vertical-align: top; }
td.small { font-size: 0.85em; } td ul { margin: 0; padding-left: 1.1em; }
"""

#: Paragraphs starting with one of these are block HTML, not wrapped in <p>.
_BLOCK_TAGS = ("<pre", "<ul", "<ol", "<div", "<table", "<details")


@dataclass
class ReportSection:
    """One titled section: free HTML paragraphs, tables and images (already data URIs)."""

    title: str
    paragraphs: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    images: list[tuple[str, str]] = field(default_factory=list)  # (caption, data URI)
    banner: tuple[str, str] | None = None  # (class "pass" / "fail" / "warn", HTML) shown before the paragraphs
    collapsed: bool = False  # a closed <details> block: secondary material the reader opens on demand


def figure_to_data_uri(fig: Any, *, dpi: int = 100) -> str:
    """Render a matplotlib figure to a PNG data URI and close it."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def image_to_data_uri(image: NDArray[Any], *, bgr: bool = True) -> str:
    """An 8-bit grey or colour image (BGR by default, as OpenCV holds it) as a PNG data URI."""
    array = np.asarray(image)
    if array.ndim == 3 and bgr:
        array = array[..., ::-1]
    buffer = io.BytesIO()
    plt.imsave(buffer, array, format="png", cmap="gray" if array.ndim == 2 else None, vmin=0, vmax=255)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def html_table(headers: Sequence[str], rows: Sequence[Sequence[Any]], *, row_classes: Sequence[str] = (),
               caption: str = "", left: Sequence[int] = ()) -> str:
    """An HTML table; cells are escaped, floats shown with 4 significant digits.

    ``caption`` (plain text) titles the table; ``left`` lists column indices holding text to align left.
    """

    def cell(value: Any) -> str:
        if isinstance(value, float):
            return f"{value:.4g}"
        return html.escape("" if value is None else str(value))

    def attr(j: int) -> str:
        return " class='text'" if j in left else ""

    head = "".join(f"<th{attr(j)}>{html.escape(h)}</th>" for j, h in enumerate(headers))
    body = []
    for i, row in enumerate(rows):
        cls = f' class="{row_classes[i]}"' if i < len(row_classes) and row_classes[i] else ""
        body.append(f"<tr{cls}>" + "".join(f"<td{attr(j)}>{cell(v)}</td>" for j, v in enumerate(row)) + "</tr>")
    cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
    return f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def _section_html(section: ReportSection) -> list[str]:
    title = html.escape(section.title)
    parts = [f"<details><summary>{title}</summary>" if section.collapsed else f"<h2>{title}</h2>"]
    if section.banner is not None:
        parts.append(f"<div class='banner {section.banner[0]}'>{section.banner[1]}</div>")
    parts.extend(p if p.startswith(_BLOCK_TAGS) else f"<p>{p}</p>" for p in section.paragraphs)
    parts.extend(section.tables)
    for caption, uri in section.images:
        parts.append(f"<figure><img src='{uri}' alt='{html.escape(caption)}'>"
                     f"<figcaption class='note'>{html.escape(caption)}</figcaption></figure>")
    if section.collapsed:
        parts.append("</details>")
    return parts


def render_report(title: str, sections: Sequence[ReportSection], *, subtitle: str = "") -> str:
    """The whole page as one self-contained HTML string."""
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>",
             f"<style>{_STYLE}</style></head><body><h1>{html.escape(title)}</h1>"]
    if subtitle:
        parts.append(f"<p class='note'>{html.escape(subtitle)}</p>")
    for section in sections:
        parts.extend(_section_html(section))
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(path: str | Path, title: str, sections: Sequence[ReportSection], *,
                 subtitle: str = "", force: bool = False) -> Path:
    """Write the report atomically to ``path`` (refusing to overwrite unless ``force``)."""
    return atomic_write_text(path, render_report(title, sections, subtitle=subtitle), force=force)

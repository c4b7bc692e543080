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
"""


@dataclass
class ReportSection:
    """One titled section: free HTML paragraphs, tables and images (already data URIs)."""

    title: str
    paragraphs: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    images: list[tuple[str, str]] = field(default_factory=list)  # (caption, data URI)


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


def html_table(headers: Sequence[str], rows: Sequence[Sequence[Any]], *, row_classes: Sequence[str] = ()) -> str:
    """An HTML table; cells are escaped, floats shown with 4 significant digits."""

    def cell(value: Any) -> str:
        if isinstance(value, float):
            return f"{value:.4g}"
        return html.escape("" if value is None else str(value))

    head = "".join(f"<th>{html.escape(h)}</th>" for h in headers)
    body = []
    for i, row in enumerate(rows):
        cls = f' class="{row_classes[i]}"' if i < len(row_classes) and row_classes[i] else ""
        body.append(f"<tr{cls}>" + "".join(f"<td>{cell(v)}</td>" for v in row) + "</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def render_report(title: str, sections: Sequence[ReportSection], *, subtitle: str = "") -> str:
    """The whole page as one self-contained HTML string."""
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>",
             f"<style>{_STYLE}</style></head><body><h1>{html.escape(title)}</h1>"]
    if subtitle:
        parts.append(f"<p class='note'>{html.escape(subtitle)}</p>")
    for section in sections:
        parts.append(f"<h2>{html.escape(section.title)}</h2>")
        parts.extend(f"<p>{p}</p>" for p in section.paragraphs)
        parts.extend(section.tables)
        for caption, uri in section.images:
            parts.append(f"<figure><img src='{uri}' alt='{html.escape(caption)}'>"
                         f"<figcaption class='note'>{html.escape(caption)}</figcaption></figure>")
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(path: str | Path, title: str, sections: Sequence[ReportSection], *,
                 subtitle: str = "", force: bool = False) -> Path:
    """Write the report atomically to ``path`` (refusing to overwrite unless ``force``)."""
    return atomic_write_text(path, render_report(title, sections, subtitle=subtitle), force=force)

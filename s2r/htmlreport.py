"""Self-contained HTML reports: tables and matplotlib figures embedded as base64 PNG data URIs.

Shared by ``s2r calibrate --report``, ``s2r validate --report`` and ``s2r depth-quality --report``. Every page
goes through one Jinja2 environment with autoescaping: a plain ``str`` anywhere in a :class:`ReportSection`
(title, paragraph, table, caption, banner) is shown as text, never parsed as markup. Markup is only what this
module builds (:func:`html_table`, :func:`html_fragment`, both returning :class:`markupsafe.Markup`), and every
value interpolated there is escaped too. Each page carries a Content-Security-Policy that allows no script, no
external resource and images from ``data:`` URIs only. Uses matplotlib's Agg backend only.
"""

from __future__ import annotations

import base64
import functools
import hashlib
import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import jinja2
import matplotlib
from markupsafe import Markup

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from s2r.fileio import OutputBatch, atomic_write_text

__all__ = [
    "CONTENT_SECURITY_POLICY",
    "Markup",
    "ReportSection",
    "figure_to_data_uri",
    "html_fragment",
    "html_table",
    "image_to_data_uri",
    "render_report",
    "write_report",
]

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

_STYLE_HASH = base64.b64encode(hashlib.sha256(_STYLE.encode("utf-8")).digest()).decode("ascii")

#: No script of any kind, nothing fetched: images from data: URIs only, the one inline style sheet by its hash.
CONTENT_SECURITY_POLICY = (f"default-src 'none'; img-src data:; style-src 'sha256-{_STYLE_HASH}'; "
                           "script-src 'none'; object-src 'none'; base-uri 'none'; form-action 'none'")

#: Markup paragraphs starting with one of these are block HTML, not wrapped in <p>.
_BLOCK_TAGS = ("<pre", "<ul", "<ol", "<div", "<table", "<details", "<h3")
_DATA_URI = "data:image/png;base64,"
_BANNER_CLASSES = ("pass", "fail", "warn")

_PAGE = """<!DOCTYPE html>
<html><head><meta charset='utf-8'>
<meta http-equiv='Content-Security-Policy' content="{{ csp }}">
<title>{{ title }}</title>
<style>{{ style }}</style></head><body><h1>{{ title }}</h1>
{% if subtitle %}<p class='note'>{{ subtitle }}</p>
{% endif %}{% for s in sections %}
{% if s.collapsed %}<details><summary>{{ s.title }}</summary>{% else %}<h2>{{ s.title }}</h2>{% endif %}
{% if s.banner %}<div class='banner {{ s.banner[0] }}'>{{ s.banner[1] }}</div>
{% endif %}{% for p in s.paragraphs %}{% if p is block %}{{ p }}{% else %}<p>{{ p }}</p>{% endif %}
{% endfor %}{% for t in s.tables %}{{ t }}
{% endfor %}{% for caption, uri in s.images %}<figure><img src='{{ uri }}' alt='{{ caption }}'><figcaption \
class='note'>{{ caption }}</figcaption></figure>
{% endfor %}{% if s.collapsed %}</details>{% endif %}{% endfor %}
</body></html>
"""

_TABLE = (
    "<table>{% if caption %}<caption>{{ caption }}</caption>{% endif %}<thead><tr>"
    "{% for h in headers %}<th{% if loop.index0 in left %} class='text'{% endif %}>{{ h }}</th>{% endfor %}"
    "</tr></thead><tbody>{% for row, cls in rows %}<tr{% if cls %} class=\"{{ cls }}\"{% endif %}>"
    "{% for v in row %}<td{% if loop.index0 in left %} class='text'{% endif %}>{{ v | cell }}</td>{% endfor %}"
    "</tr>{% endfor %}</tbody></table>"
)


def _cell(value: Any) -> str:
    """A table cell's text: floats with 4 significant digits, None empty, anything else ``str`` (escaped later)."""
    if isinstance(value, float):
        return f"{value:.4g}"
    return "" if value is None else str(value)


def _is_block(value: Any) -> bool:
    """A :class:`Markup` paragraph that is already a block element (no <p> around it)."""
    return isinstance(value, Markup) and value.lstrip().startswith(_BLOCK_TAGS)


@functools.cache
def _environment() -> jinja2.Environment:
    env = jinja2.Environment(autoescape=True, undefined=jinja2.StrictUndefined, keep_trailing_newline=True)
    env.filters["cell"] = _cell
    env.tests["block"] = _is_block
    return env


@functools.lru_cache(maxsize=256)
def _template(source: str) -> jinja2.Template:
    return _environment().from_string(source)


def html_fragment(template: str, /, **values: Any) -> Markup:
    """A piece of HTML from a Jinja2 ``template`` (a constant written in s2r, never built from input) with
    ``values`` substituted, each escaped unless it is already :class:`Markup`.

    Example: ``html_fragment("<ul>{% for w in warnings %}<li>{{ w }}</li>{% endfor %}</ul>", warnings=ws)``.
    """
    return Markup(_template(template).render(**values))


@dataclass
class ReportSection:
    """One titled section: paragraphs, tables and images (data URIs).

    Plain ``str`` paragraphs, titles, captions and banner texts are shown as text (escaped); only
    :class:`Markup` (from :func:`html_table` / :func:`html_fragment`) is inserted as HTML.
    """

    title: str
    paragraphs: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    images: list[tuple[str, str]] = field(default_factory=list)  # (caption, data URI)
    banner: tuple[str, str] | None = None  # (class "pass" / "fail" / "warn", text or Markup) before the paragraphs
    collapsed: bool = False  # a closed <details> block: secondary material the reader opens on demand


def figure_to_data_uri(fig: Any, *, dpi: int = 100) -> str:
    """Render a matplotlib figure to a PNG data URI and close it."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return _DATA_URI + base64.b64encode(buffer.getvalue()).decode("ascii")


def image_to_data_uri(image: NDArray[Any], *, bgr: bool = True) -> str:
    """An 8-bit grey or colour image (BGR by default, as OpenCV holds it) as a PNG data URI."""
    array = np.asarray(image)
    if array.ndim == 3 and bgr:
        array = array[..., ::-1]
    buffer = io.BytesIO()
    plt.imsave(buffer, array, format="png", cmap="gray" if array.ndim == 2 else None, vmin=0, vmax=255)
    return _DATA_URI + base64.b64encode(buffer.getvalue()).decode("ascii")


def html_table(headers: Sequence[str], rows: Sequence[Sequence[Any]], *, row_classes: Sequence[str] = (),
               caption: str = "", left: Sequence[int] = ()) -> Markup:
    """An HTML table; every header, cell and the caption escaped, floats shown with 4 significant digits.

    ``caption`` (plain text) titles the table; ``left`` lists column indices holding text to align left;
    ``row_classes`` are CSS classes of the rows (``pass`` / ``fail`` / ``warn`` / empty).
    """
    classes = [row_classes[i] if i < len(row_classes) else "" for i in range(len(rows))]
    return html_fragment(_TABLE, headers=list(headers), rows=list(zip(rows, classes, strict=True)),
                         caption=caption, left=set(left))


def _checked(section: ReportSection) -> ReportSection:
    """``section`` with a banner class outside pass/fail/warn and images that are not PNG data URIs refused."""
    if section.banner is not None and section.banner[0] not in _BANNER_CLASSES:
        raise ValueError(f"banner class {section.banner[0]!r} is not one of {_BANNER_CLASSES}")
    for caption, uri in section.images:
        if not uri.startswith(_DATA_URI):
            raise ValueError(f"image {caption!r} is not a PNG data URI")
    return section


def render_report(title: str, sections: Sequence[ReportSection], *, subtitle: str = "") -> str:
    """The whole page as one self-contained HTML string."""
    return _template(_PAGE).render(csp=CONTENT_SECURITY_POLICY, title=title, style=Markup(_STYLE),
                                   subtitle=subtitle, sections=[_checked(s) for s in sections])


def write_report(path: str | Path, title: str, sections: Sequence[ReportSection], *,
                 subtitle: str = "", force: bool = False, batch: OutputBatch | None = None) -> Path:
    """Write the report atomically to ``path`` (refusing to overwrite unless ``force``), or stage it in
    ``batch`` (published with the other files of that batch)."""
    page = render_report(title, sections, subtitle=subtitle)
    if batch is not None:
        return batch.add_text(path, page)
    return atomic_write_text(path, page, force=force)

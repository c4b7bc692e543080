"""A hostile name (recording folder, image file, profile source, note, warning) never becomes markup in a
report: the written page is parsed (no <script>, no on* attribute, no element from the name, the name shown as
text) and, with Chromium installed, loaded in a headless browser that must run no script from it."""

from __future__ import annotations

import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import pytest

from s2r.htmlreport import CONTENT_SECURITY_POLICY, ReportSection, html_table, write_report
from s2r.quality.metrics import FrameQuality
from s2r.quality.report import write_quality_report
from s2r.quality.run import QualityResult
from s2r.validate.recording.compare import RecordingComparison
from s2r.validate.report import write_validation_report
from tests.validate.test_report_layout import _result

HOSTILE = "<img src=x onerror=\"document.title='pwned'\"><script>document.title='pwned'</script>"
CHROMIUM = "/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else (shutil.which("chromium") or "")


class _Elements(HTMLParser):
    """Every start tag with its attributes, and the page's text."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, list[tuple[str, str | None]]]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, attrs))

    def handle_data(self, data: str) -> None:
        self.text.append(data)


def _parse(page: Path) -> _Elements:
    parser = _Elements()
    parser.feed(page.read_text(encoding="utf-8"))
    parser.close()
    return parser


def _quality(source: str) -> QualityResult:
    frame = FrameQuality(HOSTILE + ".png", 1.0, 0.5, 0.3, 0.05, 99.0, 100, 99, note="note " + HOSTILE)
    return QualityResult(profile="real", source=source, fb_px_m=40.0, frames=[frame], bins=[])


def _hostile_validation(tmp_path: Path) -> Path:
    result = _result()
    result.notes.append("note " + HOSTILE)
    result.recording = RecordingComparison(folder=HOSTILE, pattern=(9, 6), square_m=0.025,
                                           real=_quality(HOSTILE), sim=_quality("sim " + HOSTILE))
    return write_validation_report(result, tmp_path / "report")


def _assert_inert(page: Path) -> None:
    parsed = _parse(page)
    tags = [tag for tag, _ in parsed.tags]
    assert "script" not in tags
    handlers = [(tag, name) for tag, attrs in parsed.tags for name, _ in attrs if name.startswith("on")]
    assert handlers == []
    sources = [value for tag, attrs in parsed.tags if tag == "img" for name, value in attrs if name == "src"]
    assert sources and all((value or "").startswith("data:image/png;base64,") for value in sources)
    assert HOSTILE in "".join(parsed.text)  # shown, as text
    csp = [dict(attrs) for tag, attrs in parsed.tags if tag == "meta" and ("http-equiv", "Content-Security-Policy")
           in attrs]
    assert csp and csp[0]["content"] == CONTENT_SECURITY_POLICY and "script-src 'none'" in CONTENT_SECURITY_POLICY


def test_validation_report_shows_a_hostile_recording_name_as_text(tmp_path: Path) -> None:
    _assert_inert(_hostile_validation(tmp_path))


def test_quality_report_shows_hostile_file_names_as_text(tmp_path: Path) -> None:
    page = write_quality_report(_quality(HOSTILE), tmp_path / "q")
    parsed = _parse(page)
    assert "script" not in [tag for tag, _ in parsed.tags]
    assert HOSTILE + ".png" in "".join(parsed.text)


def test_plain_strings_in_sections_are_text_and_tables_escape_every_cell(tmp_path: Path) -> None:
    table = html_table([HOSTILE], [[HOSTILE, 1.23456]], caption=HOSTILE, row_classes=["x' onmouseover='a"])
    section = ReportSection(HOSTILE, paragraphs=[HOSTILE, "<pre>" + HOSTILE], tables=[table, HOSTILE],
                            banner=("warn", HOSTILE))
    page = write_report(tmp_path / "r.html", HOSTILE, [section], subtitle=HOSTILE)
    parsed = _parse(page)
    assert [tag for tag, _ in parsed.tags if tag in ("script", "img", "pre")] == []
    assert [name for _, attrs in parsed.tags for name, _ in attrs if name.startswith("on")] == []
    assert "1.235" in "".join(parsed.text)


def test_a_banner_class_or_image_from_outside_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="banner class"):
        write_report(tmp_path / "a.html", "t", [ReportSection("s", banner=("x' onclick='y", "b"))])
    with pytest.raises(ValueError, match="PNG data URI"):
        write_report(tmp_path / "b.html", "t", [ReportSection("s", images=[("c", "javascript:alert(1)")])])
    assert not list(tmp_path.iterdir())


@pytest.mark.browser
def test_no_script_runs_in_headless_chromium(tmp_path: Path) -> None:
    if not CHROMIUM:
        pytest.skip("chromium is not installed (make test-browser installs it)")
    page = _hostile_validation(tmp_path)
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking",
             "--disable-component-update", "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}"]
    dom = subprocess.run([CHROMIUM, *flags, "--dump-dom", page.as_uri()], capture_output=True, text=True,
                         timeout=120, check=False).stdout
    assert "<title>s2r validate:" in dom and "pwned" not in dom.split("</title>")[0]
    assert "<script" not in dom and 'src="x"' not in dom
    assert "&lt;script&gt;document.title='pwned'&lt;/script&gt;" in dom  # the name, shown as text

"""A depth file named like markup goes through ``depth-quality --report`` end to end: the written page holds no
script, no event-handler attribute and no element from the name, and shows the name as text (the HTML writer
escapes every value; a Content-Security-Policy forbids scripts anyway). The browser check of the same rule is
tests/validate/test_report_hostile.py (``make test-browser``)."""

from __future__ import annotations

from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main

NAME = "<img src=x onerror=alert(1)><svg onload=alert(2)><script>alert(3)"  # no "/": it is a file name


class _Tags(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, list[tuple[str, str | None]]]] = []
        self.text = ""

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, attrs))

    def handle_data(self, data: str) -> None:
        self.text += data


def test_a_markup_file_name_is_text_in_the_depth_quality_report(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "depth"
    folder.mkdir()
    np.save(folder / f"{NAME}.npy", np.full((480, 848), 1.0, np.float32))
    report = tmp_path / "report"
    code = main(["-q", "depth-quality", "realsense_d435_848x480", "--depth", str(folder), "--wall", "--distance",
                 "1.0", "--report", str(report)])
    assert code == 0, capsys.readouterr().err
    parser = _Tags()
    parser.feed((report / "depth_quality.html").read_text(encoding="utf-8"))
    assert [tag for tag, _ in parser.tags if tag in ("script", "svg")] == []
    images = [dict(attrs).get("src") or "" for tag, attrs in parser.tags if tag == "img"]
    assert all(src.startswith("data:image/png;base64,") for src in images)  # s2r's own figures only
    assert [name for _, attrs in parser.tags for name, _ in attrs if name.startswith("on")] == []
    assert f"{NAME}.npy" in parser.text
    assert any(tag == "meta" and ("http-equiv", "Content-Security-Policy") in attrs for tag, attrs in parser.tags)

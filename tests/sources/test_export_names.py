"""Issue 23: a profile's name cannot break the export's XML comment or markup; s2r's own reader accepts every
export (hostile names: ``--``, ``-->``, ``<``, ``&``, control characters)."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import SourceError
from s2r.formats.s2r_yaml import dump_profile
from s2r.registry import load_profile
from s2r.sources import load_description_profile
from s2r.sources.export.gazebo import EXPORT_FORMATS, comment_text, export_gazebo
from s2r.sources.xmlparse import parse_xml
from tests.conftest import make_rig

SUFFIX = {"urdf": "urdf", "sdf": "sdf", "gz-sim": "sdf"}


def test_comment_text_never_holds_a_double_hyphen() -> None:
    assert comment_text("cam--v2") == "cam- -v2"
    assert comment_text("a-->b") == "a- ->b"
    assert comment_text("x---") == "x- - - "  # a comment may not end in '-' either ('--->' is '--' + '->')
    assert comment_text("ok<&>\x1b]0;t\x07") == "ok<&>?]0;t?"


def test_cam_v2_through_the_cli_reads_back(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The reproducer: the name pattern allows ``cam--v2``; the export used to write ``--`` in its comment."""
    src = dump_profile(make_rig(name="cam--v2"), tmp_path / "cam.yaml")
    for fmt in EXPORT_FORMATS:
        xml = tmp_path / f"cam_{fmt}.{SUFFIX[fmt]}"
        assert main(["profile", "export-gazebo", str(src), "--format", fmt, "-o", str(xml)]) == 0
        assert "cam- -v2" in xml.read_text().splitlines()[1]
        out = tmp_path / f"back_{fmt}.yaml"
        assert main(["profile", "from-urdf", str(xml), "-o", str(out), "--convention", "exact"]) == 0, \
            capsys.readouterr().err
        assert load_profile(out).baseline_m == pytest.approx(0.1, abs=1e-9)


@pytest.mark.parametrize("name", ["a--b", "a-->b", "x-", "a<b", "a&b", "q\"'>"])
@pytest.mark.parametrize("fmt", EXPORT_FORMATS)
def test_hostile_names_export_to_xml_that_s2r_reads(tmp_path: Path, name: str, fmt: str) -> None:
    profile = make_rig().model_copy(update={"name": name})  # past the name pattern, as a library caller could
    text, _ = export_gazebo(profile, fmt=fmt)
    path = tmp_path / f"rig.{SUFFIX[fmt]}"
    path.write_text(text)
    back = load_description_profile(path, convention="exact")
    assert back.baseline_m == pytest.approx(0.1, abs=1e-9)
    assert text.count("-->") == 1 and "<!--" in text.splitlines()[1]


@pytest.mark.parametrize("name", ["cam\x1b[31m", "bell\x07", "nul\x00x"])
def test_control_characters_are_refused_not_written(name: str) -> None:
    with pytest.raises(SourceError, match="which no XML file can carry"):
        export_gazebo(make_rig().model_copy(update={"name": name}), fmt="sdf")


def test_parent_link_with_a_control_character(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = dump_profile(make_rig(), tmp_path / "rig.yaml")
    out = tmp_path / "r.urdf"
    assert main(["profile", "export-gazebo", str(src), "--parent-link", "base\x1b[2J", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--parent-link" in err and "\\x1b" in err and "\x1b" not in err and not out.exists()
    assert main(["profile", "export-gazebo", str(src), "--parent-link", "base<&>--link", "-o", str(out)]) == 0
    root = parse_xml(out.read_text(), out).root  # the snippet mounts on a link it does not declare: XML only
    assert [j.find("parent").get("link") for j in root.iter("joint") if j.get("name", "").endswith("mount_joint")] \
        == ["base<&>--link"]

"""Issue 24 item 4: Clearpath robots switch payloads on with environment variables (``$(optenv JACKAL_BB2 0)``);
``--env NAME=VALUE`` is what ``$(env)`` / ``$(optenv)`` see, the machine's environment is never read, and the
profile records what was passed. Fixture: tests/sources/fixtures/clearpath (excerpts written for s2r's tests)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import SourceError
from s2r.registry import load_profile
from s2r.sources import lint_description, load_description_profile

CLEARPATH = Path(__file__).parent / "fixtures" / "clearpath"
JACKAL = CLEARPATH / "jackal_description" / "urdf" / "jackal.urdf.xacro"


def _from_urdf(tmp_path: Path, capsys: pytest.CaptureFixture[str], *extra: str) -> tuple[int, str, Path]:
    out = tmp_path / "p.yaml"
    code = main(["profile", "from-urdf", str(JACKAL), "--package-path", str(CLEARPATH), "-o", str(out), *extra])
    captured = capsys.readouterr()
    return code, captured.out + captured.err, out


def test_without_env_the_cameras_are_off_and_the_error_names_env(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("JACKAL_BB2", "1")  # set on the machine only: never read
    code, text, out = _from_urdf(tmp_path, capsys)
    assert code == 2 and "no camera sensor found" in text and "--env NAME=VALUE" in text and "JACKAL_BB2" in text
    assert not out.exists()


def test_bumblebee2_through_env(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """BB2-08S2C-38: 1024x768, hfov 1.15191730632 rad -> fx = 512 / tan(0.57595865316) = 788.41 px; B = 0.120 m."""
    code, text, out = _from_urdf(tmp_path, capsys, "--env", "JACKAL_BB2=1")
    assert code == 0, text
    profile = load_profile(out)
    assert (profile.left.width_px, profile.left.height_px) == (1024, 768)
    assert profile.left.fx_px == pytest.approx(512 / math.tan(1.15191730632 / 2), abs=1e-9)
    # the cameras' pose rotation 1.5707 (not pi/2) tilts the 0.12 m baseline by 9.6e-5 rad: 1.2e-5 m in y
    assert pytest.approx([-0.12, 0.0, 0.0], abs=2e-5) == profile.T
    assert "--env JACKAL_BB2=1" in profile.provenance.notes


def test_flea3_stereo_and_its_separation_through_env(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Cameras at y = +-JACKAL_STEREO_SEPERATION: 0.32 m apart by default, 0.2 m with 0.1; fx = 320 / tan(pi/6)."""
    code, text, out = _from_urdf(tmp_path, capsys, "--env", "JACKAL_STEREO_FLEA3=1")
    assert code == 0, text
    assert load_profile(out).baseline_m == pytest.approx(0.32, abs=1e-9)
    code, text, out = _from_urdf(tmp_path, capsys, "--env", "JACKAL_STEREO_FLEA3=1", "--env",
                                 "JACKAL_STEREO_SEPERATION=0.1", "--force")
    assert code == 0, text
    profile = load_profile(out)
    assert profile.baseline_m == pytest.approx(0.2, abs=1e-9)
    assert profile.left.fx_px == pytest.approx(320 / math.tan(math.pi / 6), abs=1e-6)
    assert "--env JACKAL_STEREO_FLEA3=1 JACKAL_STEREO_SEPERATION=0.1" in profile.provenance.notes


def test_lint_takes_env_too(capsys: pytest.CaptureFixture[str]) -> None:
    findings = lint_description(JACKAL, package_paths=[CLEARPATH], env={"JACKAL_BB2": "1"})
    assert not [f for f in findings if f.severity == "error"]
    assert main(["lint", str(JACKAL), "--package-path", str(CLEARPATH), "--env", "JACKAL_BB2=1"]) == 0
    assert "0 error(s)" in capsys.readouterr().out


def test_env_substitution_sees_only_passed_values(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    extra = '<link name="base_link"/><link name="$(env ROBOT)_x"/>'
    text = JACKAL.read_text().replace('<link name="base_link"/>', extra)
    path = tmp_path / "desc" / "jackal.urdf.xacro"
    path.parent.mkdir()
    path.write_text(text)
    (path.parent / "empty.urdf").write_text((JACKAL.parent / "empty.urdf").read_text())
    monkeypatch.setenv("ROBOT", "machine")
    with pytest.raises(SourceError, match=r"\$\(env ROBOT\) is refused.*pass --env ROBOT=VALUE"):
        load_description_profile(path, package_paths=[CLEARPATH], env={"JACKAL_BB2": "1"})
    profile = load_description_profile(path, package_paths=[CLEARPATH], env={"JACKAL_BB2": "1", "ROBOT": "r7"})
    assert "ROBOT=r7" in profile.provenance.notes


@pytest.mark.parametrize("bad", ["JACKAL_BB2", "=1", "A B=1", "É=1"])
def test_bad_env_items_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str], bad: str) -> None:
    code, text, _ = _from_urdf(tmp_path, capsys, "--env", bad)
    assert code == 2 and "--env NAME=VALUE" in text and text.count("\n") == 1

"""``s2r render boards | scene`` through s2r.cli.main: outputs, JSON, one-line errors with exit code 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.cli.render_cmd import SCENE_CHOICES
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import SimulationSettings, StereoProfile
from s2r.render import SCENES


@pytest.fixture
def profile_path(rig: StereoProfile, tmp_path: Path) -> Path:
    return dump_profile(rig, tmp_path / "rig.yaml")


def test_boards_command_writes_a_set(profile_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "boards"
    code = main(["render", "boards", str(profile_path), "--views", "2", "--out", str(out), "--supersample", "1",
                 "--pattern", "8x5", "--square", "0.03", "--seed", "4", "--jobs", "1", "--json"])
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    assert report["views"] == 2 and Path(report["truth"]).name == "truth.yaml"
    assert sorted(p.name for p in (out / "right").iterdir()) == ["00.png", "01.png"]


def test_scene_command_writes_ground_truth(profile_path: Path, tmp_path: Path,  # -o, as every command; --out too
                                           capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "scene"
    code = main(["render", "scene", str(profile_path), "--scene", "planes", "--distances", "1,2", "-o", str(out),
                 "--supersample", "1", "--jobs", "1"])
    assert code == 0
    assert "2 planes frame(s)" in capsys.readouterr().out
    assert sorted(p.name for p in (out / "disparity").iterdir()) == ["00.npy", "01.npy"]
    assert SCENE_CHOICES == SCENES


def test_full_output_folder_exits_2(profile_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "full"
    out.mkdir()
    (out / "x.png").write_bytes(b"")
    for cmd in (["boards", str(profile_path), "--views", "1"], ["scene", str(profile_path)]):
        assert main(["render", *cmd, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: ") and "--force" in err and "\n" not in err


def test_clip_planes_and_big_pattern_exit_2(rig: StereoProfile, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    short = rig.model_copy(update={"simulation": SimulationSettings(clip_near_m=0.05, clip_far_m=0.2)})
    path = dump_profile(short, tmp_path / "short.yaml")
    assert main(["render", "boards", str(path), "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip()
    assert "simulation.clip_far_m" in err and "raise clip_far_m" in err and "\n" not in err
    path = dump_profile(rig, tmp_path / "rig2.yaml")
    assert main(["render", "boards", str(path), "--pattern", "60x40", "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: pattern: ") and "--pattern" in err and "\n" not in err
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


@pytest.mark.parametrize("argv", [
    ["boards", "PROFILE", "--pattern", "9by6"], ["scene", "PROFILE", "--distances", "1,x"],
    ["scene", "PROFILE", "--scene", "forest"],
])
def test_malformed_options_are_usage_errors(profile_path: Path, tmp_path: Path, argv: list[str]) -> None:
    argv = [str(profile_path) if a == "PROFILE" else a for a in argv]
    with pytest.raises(SystemExit) as info:
        main(["render", *argv, "--out", str(tmp_path / "o")])
    assert info.value.code == 2

"""s2r check / fleet check against hostile and careless inputs: every refusal is one line, nothing is written
outside -o, a swapped or duplicated pair is named, not judged. Recordings come from tests/drift/warp_gen.py."""

from __future__ import annotations

import json
import os
import socket
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import StereoProfile
from tests.conftest import make_rig
from tests.drift.warp_gen import Cam, render_pair, rotvec_matrix

SIZE = (320, 240)


def small_rig() -> StereoProfile:
    return make_rig(name="hostile_rig", width=SIZE[0], height=SIZE[1], hfov_rad=1.1, baseline_m=0.08,
                    rotation_deg=(0.2, -0.3, 0.1), origin="real")


def _write(folder: Path, profile: StereoProfile, *, frames: int, turn_deg: tuple[float, float, float] = (0, 0, 0),
           swap: bool = False) -> Path:
    c = profile.left
    cam = Cam(c.width_px, c.height_px, c.fx_px, c.fy_px, c.cx_px, c.cy_px)
    for side in ("left", "right"):
        (folder / side).mkdir(parents=True, exist_ok=True)
    for k in range(frames):
        left, right = render_pair(cam, cam, profile.R, profile.T.reshape(3), rotvec_matrix(np.radians(turn_deg)),
                                  seed=50 + k, plane_depth_m=0.8)
        if swap:
            left, right = right, left
        cv2.imwrite(str(folder / "left" / f"{k:02d}.png"), left)
        cv2.imwrite(str(folder / "right" / f"{k:02d}.png"), right)
    return folder


@pytest.fixture(scope="module")
def base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("hostile_drift")
    dump_profile(small_rig(), root / "rig.yaml")
    _write(root / "rec", small_rig(), frames=2)
    return root


def _err(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    return err.splitlines()[-1]


def test_images_of_another_size_are_one_line_naming_the_file(capsys: pytest.CaptureFixture[str], base: Path) -> None:
    assert main(["check", "realsense_d435_848x480", str(base / "rec")]) == 2
    err = _err(capsys)
    assert err.startswith(f"error: {base / 'rec' / 'left' / '00.png'}: image size:") and "848x480" in err


def test_a_recording_of_fifos_or_devices_is_bad_input(capsys: pytest.CaptureFixture[str], base: Path,
                                                      tmp_path: Path) -> None:
    for side in ("left", "right"):
        (tmp_path / side).mkdir()
    (tmp_path / "left" / "00.png").write_bytes((base / "rec" / "left" / "00.png").read_bytes())
    os.mkfifo(tmp_path / "right" / "00.png")
    (tmp_path / "right" / "01.png").symlink_to("/dev/zero")
    assert main(["check", str(base / "rig.yaml"), str(tmp_path)]) == 2
    assert "1 left image and no right images" in _err(capsys)  # a FIFO or a device is not an image file


def test_identical_and_swapped_pairs_are_named_not_judged(capsys: pytest.CaptureFixture[str], base: Path,
                                                          tmp_path: Path) -> None:
    twice = tmp_path / "twice"
    for side in ("left", "right"):
        (twice / side).mkdir(parents=True)
        (twice / side / "00.png").write_bytes((base / "rec" / "left" / "00.png").read_bytes())
    assert main(["check", str(base / "rig.yaml"), str(twice), "--json"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert result["verdict"] == "cannot tell" and "same image" in result["reasons"][0]
    assert result["rotation_error_deg"]["roll"] is None  # not estimated is not a confident zero
    swapped = _write(tmp_path / "swapped", small_rig(), frames=1, swap=True)
    assert main(["check", str(base / "rig.yaml"), str(swapped), "--json"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert result["verdict"] == "cannot tell" and "look exchanged" in result["reasons"][0]
    assert result["swap"]["found"] == "exchanged" and result["rotation_error_deg"]["yaw"] is None


def test_one_frame_is_enough_to_judge(capsys: pytest.CaptureFixture[str], base: Path, tmp_path: Path) -> None:
    one = tmp_path / "one"
    for side in ("left", "right"):
        (one / side).mkdir(parents=True)
        (one / side / "00.png").write_bytes((base / "rec" / side / "00.png").read_bytes())
    assert main(["check", str(base / "rig.yaml"), str(one), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["verdict"] == "good" and result["sigma_resampled_deg"] is not None  # jackknife over regions


@pytest.mark.parametrize("name", ["..", ".", ".hidden", "a/b", "../up", "index.html", "SUMMARY.json"])
def test_fleet_names_cannot_leave_or_shadow_the_output(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                       name: str) -> None:
    fleet = tmp_path / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": [{"name": name, "profile": "p.yaml", "recording": "r"}]}))
    assert main(["fleet", "check", str(fleet), "-o", str(tmp_path / "out")]) == 2
    assert ".name: bad or repeated name" in _err(capsys)
    assert not (tmp_path / "out").exists() and not (tmp_path / "check.html").exists()


def test_fleet_names_repeated_ignoring_case_are_refused(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    fleet = tmp_path / "fleet.yaml"
    robots = [{"name": n, "profile": "p.yaml", "recording": "r"} for n in ("R1", "r1")]
    fleet.write_text(json.dumps({"robots": robots}))
    assert main(["fleet", "check", str(fleet), "-o", str(tmp_path / "out")]) == 2
    assert "robots[1].name" in _err(capsys)


def test_a_scheduler_that_never_answers_fails_fast(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                   base: Path) -> None:
    fleet = tmp_path / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": [{"name": "a", "profile": str(base / "rig.yaml"),
                                             "recording": str(base / "rec")}]}))
    with socket.socket() as silent:  # accepts connections, never says a word
        silent.bind(("127.0.0.1", 0))
        silent.listen(4)
        address = f"tcp://127.0.0.1:{silent.getsockname()[1]}"
        start = time.monotonic()
        assert main(["fleet", "check", str(fleet), "-o", str(tmp_path / "o"), "--scheduler", address]) == 2
        waited = time.monotonic() - start
    err = _err(capsys)
    assert err.startswith(f"error: {address}: --scheduler: cannot reach the Dask scheduler")
    assert waited < 30.0  # Dask alone would wait out its 30 s tcp timeout in the handshake
    for bad in ("notanaddress", "http://127.0.0.1:1"):
        assert main(["fleet", "check", str(fleet), "-o", str(tmp_path / "o"), "--scheduler", bad]) == 2
        assert "--scheduler: cannot reach the Dask scheduler: not an address" in _err(capsys)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("below", [True, False])
def test_a_vertical_rig_is_checked_turned_on_its_side(below: bool) -> None:
    """One camera above the other: checked with images and profile turned by 90 degrees, the rotation given in
    the profile's own axes (here 0.3 deg of pitch, about the axis the turned check calls yaw)."""
    from s2r.drift.check import check_drift
    from s2r.profile import Extrinsics

    profile = make_rig(name="vertical_rig", width=400, height=300, hfov_rad=1.1, baseline_m=0.08,
                       rotation_deg=(0.2, -0.3, 0.1), origin="real")
    T = -profile.R @ np.array([0.0, 0.08 if below else -0.08, 0.0])
    vertical = profile.model_copy(update={"extrinsics": Extrinsics(
        rotation=tuple(map(tuple, profile.R.tolist())), translation_m=tuple(T.tolist()))})  # type: ignore[arg-type]
    c = vertical.left
    cam = Cam(c.width_px, c.height_px, c.fx_px, c.fy_px, c.cx_px, c.cy_px)
    turn = (0.0, 0.0, 0.3)
    pairs = [(f"{k:02d}", *render_pair(cam, cam, vertical.R, T, rotvec_matrix(np.radians(turn)), seed=9 + k))
             for k in range(2)]
    result = check_drift(vertical, pairs)
    assert result.verdict == "drifted" and "vertical rig" in result.sigma_source
    for got, truth in zip(result.omega_deg, turn, strict=True):
        assert abs(got - truth) <= max(0.03, 0.1 * abs(truth)), result.omega_deg


def test_a_fleet_output_is_published_whole_or_not_at_all(capsys: pytest.CaptureFixture[str], base: Path,
                                                         tmp_path: Path) -> None:
    fleet = tmp_path / "fleet.yaml"
    robots = [{"name": n, "profile": str(base / "rig.yaml"), "recording": str(tmp_path / "missing")}
              for n in ("a", "b")]
    fleet.write_text(json.dumps({"robots": robots}))
    out = tmp_path / "out"
    (out / "summary.json").mkdir(parents=True)  # an old output: --force replaces the folder whole
    (out / "old_robot").mkdir()
    assert main(["fleet", "check", str(fleet), "-o", str(out), "--force", "--workers", "1"]) == 1
    assert sorted(p.name for p in out.iterdir()) == ["a", "b", "index.html", "summary.json"]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".s2r-tmp-")]
    assert (out / "a" / "check.json").is_file() and not (out / "a" / "check.html").exists()  # failed: no report


def test_a_huge_fleet_file_is_refused_before_parsing(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    from s2r.drift import fleet as fleet_module

    path = tmp_path / "fleet.yaml"
    path.write_text("# padding\n" * (fleet_module.MAX_FLEET_CHARS // 10 + 1) + "robots: []\n")
    assert main(["fleet", "check", str(path), "-o", str(tmp_path / "o")]) == 2
    assert "a fleet file is at most" in _err(capsys)
    monkeypatch.setattr(fleet_module, "MAX_ROBOTS", 3)
    robots = [{"name": f"r{k}", "profile": "p.yaml", "recording": "r"} for k in range(4)]
    path.write_text(json.dumps({"robots": robots}))
    assert main(["fleet", "check", str(path), "-o", str(tmp_path / "o")]) == 2
    assert "robots: lists 4 robots; one run checks at most 3" in _err(capsys)


def test_more_local_workers_than_the_machine_holds_is_refused(capsys: pytest.CaptureFixture[str],
                                                              tmp_path: Path) -> None:
    fleet = tmp_path / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": [{"name": "a", "profile": "p.yaml", "recording": "r"}]}))
    workers = str(4 * (os.cpu_count() or 1) + 1)
    assert main(["fleet", "check", str(fleet), "-o", str(tmp_path / "o"), "--workers", workers]) == 2
    assert "--workers:" in _err(capsys) and not (tmp_path / "o").exists()


def test_fleet_paths_are_sent_absolute(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A remote scheduler's workers run elsewhere: a FLEET.yaml given by a relative path still sends absolute
    paths."""
    from s2r.drift.check import CheckSettings
    from s2r.drift.fleet import load_fleet

    (tmp_path / "site").mkdir()
    (tmp_path / "site" / "fleet.yaml").write_text(json.dumps({"robots": [
        {"name": "a", "profile": "a.yaml", "recording": "logs/a"},
        {"name": "b", "profile": "a.yaml", "recording": {"left": "l/*.png", "right": "r/*.png"}}]}))
    monkeypatch.chdir(tmp_path)
    jobs = load_fleet(Path("site/fleet.yaml"), settings=CheckSettings())
    assert jobs[0].profile == str(tmp_path / "site" / "a.yaml")
    assert jobs[0].source.folder == tmp_path / "site" / "logs" / "a"
    assert jobs[1].source.left_glob == str(tmp_path / "site" / "l" / "*.png")


def test_a_mistyped_option_of_a_command_gets_did_you_mean(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as stop:
        main(["check", "rig.yaml", "logs", "--tolernce", "0.1"])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith("unrecognized arguments: --tolernce 0.1 (did you mean --tolerance?)")
    with pytest.raises(SystemExit):
        main(["fleet", "check", "f.yaml", "-o", "o", "--schedular", "tcp://h:1"])
    assert "(did you mean --scheduler?)" in capsys.readouterr().err


def test_big_images_are_checked_downscaled_in_bounded_memory(tmp_path: Path) -> None:
    """Issue 37 class 1: a legal 8192^2 profile and one black 8192^2 pair (80 kB of PNG) took 15.6 GB; now one
    warning line, a verdict, inside the 1 GB address-space cap and the timeout of the hostile suite."""
    from tests.hostile._limits import run_s2r

    dump_profile(make_rig(name="big", width=8192, height=8192, hfov_rad=1.0, baseline_m=0.1, origin="real"),
                 tmp_path / "big.yaml")
    for side in ("left", "right"):
        (tmp_path / "rec" / side).mkdir(parents=True)
        cv2.imwrite(str(tmp_path / "rec" / side / "00.png"), np.zeros((8192, 8192), np.uint8))
    done = run_s2r("check", str(tmp_path / "big.yaml"), str(tmp_path / "rec"), timeout_s=60.0)
    assert done.returncode == 1, done.stderr
    assert "downscaled to 1145x1145 for feature detection" in done.stderr and "Traceback" not in done.stderr
    assert "CANNOT TELL" in done.stdout


def test_one_frame_and_a_diagonal_baseline_never_exit_3(capsys: pytest.CaptureFixture[str], base: Path,
                                                        tmp_path: Path) -> None:
    """Issue 37 classes 4 and 5: --max-frames 1 (ZeroDivisionError) and T = (-0.05, 0.05, 0) (LinAlgError)."""
    assert main(["check", str(base / "rig.yaml"), str(base / "rec"), "--max-frames", "1", "--json"]) in (0, 1)
    assert json.loads(capsys.readouterr().out)["verdict"] in ("good", "cannot tell")
    diagonal = small_rig().model_copy(update={"extrinsics": small_rig().extrinsics.model_copy(update={
        "rotation": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)), "translation_m": (-0.05, 0.05, 0.0)})})
    dump_profile(diagonal, tmp_path / "diagonal.yaml")
    assert main(["check", str(tmp_path / "diagonal.yaml"), str(base / "rec"), "--json"]) == 2
    err = _err(capsys)
    assert "no side-by-side or vertical rectification holds this baseline" in err and "(+0.050, -0.050" in err


def test_reversed_arguments_get_a_one_line_hint(capsys: pytest.CaptureFixture[str], base: Path) -> None:
    """Issue 34: ``s2r check logs/run1 real.yaml``."""
    assert main(["check", str(base / "rec"), str(base / "rig.yaml")]) == 2
    err = _err(capsys)
    assert "the arguments look reversed" in err and f"s2r check {base / 'rig.yaml'} {base / 'rec'}" in err

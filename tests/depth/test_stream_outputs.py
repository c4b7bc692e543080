"""Stream outputs are published whole or not at all: a bad frame mid-stream, a link or an existing output, a full
disk: one line, exit 2, nothing at the output and no temporary left beside it."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from tests.conftest import make_rig
from tests.depth.stream_inputs import write_profile
from tests.depth.synth import make_pair
from tests.hostile._limits import run_s2r


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A 320x240 ideal rig's profile and a folder of 4 synthetic pairs (left/NN.png, right/NN.png)."""
    root = tmp_path_factory.mktemp("rec")
    profile = write_profile(make_rig(name="small_rig", width=320, height=240), root / "rig.yaml")
    for side in ("left", "right"):
        (root / "rec" / side).mkdir(parents=True)
    for k in range(4):
        pair = make_pair(seed=k)
        cv2.imwrite(str(root / "rec" / "left" / f"{k:02d}.png"), pair.left)
        cv2.imwrite(str(root / "rec" / "right" / f"{k:02d}.png"), pair.right)
    return profile, root / "rec"


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(".s2r-tmp-"))


@pytest.mark.parametrize("target", ["files", "ros2", "ros1"])
def test_a_bad_frame_mid_stream_leaves_nothing(rec: tuple[Path, Path], tmp_path: Path, target: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    profile, folder = rec
    bad = tmp_path / "rec"
    for side in ("left", "right"):
        (bad / side).mkdir(parents=True)
        for k in range(4):
            (bad / side / f"{k:02d}.png").write_bytes((folder / side / f"{k:02d}.png").read_bytes())
    cv2.imwrite(str(bad / "left" / "02.png"), np.zeros((480, 640), np.uint8))  # the third frame: another size
    out = tmp_path / "out" / ("d.bag" if target == "ros1" else "d")
    assert main(["-q", "depth", str(profile), str(bad), "-o", str(out), "--to", target]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "02.png" in err and "640x480" in err
    assert not out.exists() and not _leftovers(tmp_path)
    assert not out.parent.exists() or not _leftovers(out.parent)  # an empty -o parent the run made may be removed


@pytest.mark.parametrize("target", ["files", "ros2", "ros1"])
def test_links_and_existing_outputs_are_refused(rec: tuple[Path, Path], tmp_path: Path, target: str,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    profile, folder = rec
    victim = tmp_path / "victim"
    victim.mkdir()
    link = tmp_path / "link"
    link.symlink_to(victim if target != "ros1" else victim / "x.bag")
    assert main(["-q", "depth", str(profile), str(folder), "-o", str(link), "--to", target, "--force"]) == 2
    assert "symbolic link" in capsys.readouterr().err
    assert not any(victim.iterdir())
    out = tmp_path / ("o.bag" if target == "ros1" else "o")
    assert main(["-q", "depth", str(profile), str(folder), "-o", str(out), "--to", target]) == 0
    before = sorted((p.name, p.stat().st_mtime_ns) for p in ([out] if out.is_file() else out.rglob("*")))
    assert main(["-q", "depth", str(profile), str(folder), "-o", str(out), "--to", target]) == 2
    assert "--force" in capsys.readouterr().err
    after = sorted((p.name, p.stat().st_mtime_ns) for p in ([out] if out.is_file() else out.rglob("*")))
    assert before == after
    assert main(["-q", "depth", str(profile), str(folder), "-o", str(out), "--to", target, "--force"]) == 0
    assert not _leftovers(tmp_path)


@pytest.mark.parametrize("target", ["files", "ros2", "ros1"])
def test_a_full_disk_is_one_line_and_no_half_output(rec: tuple[Path, Path], tmp_path: Path, target: str) -> None:
    profile, folder = rec
    out = tmp_path / ("o.bag" if target == "ros1" else "o")
    done = run_s2r("-q", "depth", str(profile), str(folder), "-o", str(out), "--to", target, file_size=200_000,
                   timeout_s=120)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and "cannot write" in done.stderr
    assert not out.exists() and not _leftovers(tmp_path)


def test_options_of_another_target_and_bad_positionals(rec: tuple[Path, Path], tmp_path: Path,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    profile, folder = rec
    out = str(tmp_path / "o")
    assert main(["depth", str(profile), str(folder), "-o", out, "--pcd", "--to", "ros2"]) == 2
    assert "--pcd: does not apply to --to ros2" in capsys.readouterr().err
    assert main(["depth", str(profile), str(folder), "-o", out, "--depth-encoding", "16UC1"]) == 2
    assert "--depth-encoding: does not apply to --to files" in capsys.readouterr().err
    assert main(["depth", str(profile), "a.png", "b.png", "c.png", "-o", out]) == 2
    assert "too many inputs" in capsys.readouterr().err
    assert main(["depth", str(profile), str(folder), "-o", str(folder)]) == 2
    assert "the output is the input (FOLDER " in capsys.readouterr().err
    assert main(["depth", str(profile), "--bag", str(tmp_path / "missing.bag"), "--left-topic", "/l",
                 "--right-topic", "/r", "-o", out, "--to", "ros2"]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert not (tmp_path / "o").exists() and not _leftovers(tmp_path)


def test_one_pair_into_a_bag_and_the_older_order(rec: tuple[Path, Path], tmp_path: Path) -> None:
    profile, folder = rec
    left, right = folder / "left" / "00.png", folder / "right" / "00.png"
    assert main(["-q", "depth", str(profile), str(left), str(right), "-o", str(tmp_path / "p.bag"), "--to",
                 "ros1"]) == 0
    assert (tmp_path / "p.bag").is_file()
    assert main(["-q", "depth", str(left), str(right), "--profile", str(profile), "-o", str(tmp_path / "d")]) == 0
    assert main(["-q", "depth", str(profile), str(left), str(right), "-o", str(tmp_path / "e")]) == 0
    assert (np.load(tmp_path / "d" / "disparity.npy").tobytes() ==
            np.load(tmp_path / "e" / "disparity.npy").tobytes())
    assert main(["-q", "depth", str(profile), str(left), str(right), "-o", str(tmp_path / "f"), "--pcd"]) == 2
    assert main(["-q", "depth", str(profile), str(left), str(right), "-o", str(tmp_path / "f"), "--namespace",
                 "/x"]) == 2
    assert main(["-q", "depth", str(profile), str(left), str(right), "-o", str(tmp_path / "f"), "--points"]) == 0
    assert (tmp_path / "f" / "points.ply").is_file()


@pytest.mark.parametrize("kind", ["ros1", "ros2"])
def test_force_never_writes_over_the_input_bag(rec: tuple[Path, Path], tmp_path: Path, kind: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """-o naming the input bag (or a path inside a ROS 2 bag folder) is refused even with --force; the bag is kept."""
    from tests.recordings.helpers import write_bag

    profile, folder = rec
    pair = (cv2.imread(str(folder / "left" / "00.png"), cv2.IMREAD_GRAYSCALE),
            cv2.imread(str(folder / "right" / "00.png"), cv2.IMREAD_GRAYSCALE))
    bag = write_bag(tmp_path / ("in.bag" if kind == "ros1" else "in"), [pair], kind="ros1" if kind == "ros1" else
                    "sqlite3")
    before = sorted((p.name, p.stat().st_size) for p in ([bag] if bag.is_file() else bag.iterdir()))
    for out in (bag, bag / "sub") if kind == "ros2" else (bag,):
        assert main(["depth", str(profile), "--bag", str(bag), "--left-topic", "/l", "--right-topic", "/r", "-o",
                     str(out), "--to", kind, "--force"]) == 2
        assert "the output is the input (--bag " in capsys.readouterr().err
    assert sorted((p.name, p.stat().st_size) for p in ([bag] if bag.is_file() else bag.iterdir())) == before


def test_thinning_and_namespace_are_never_ignored(rec: tuple[Path, Path], tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """--every / --max-frames apply to recordings only, and --namespace must be a ROS namespace: either is refused
    in one line rather than silently ignored or written into topic names."""
    profile, folder = rec
    left, right = folder / "left" / "00.png", folder / "right" / "00.png"
    assert main(["depth", str(profile), str(left), str(right), "-o", str(tmp_path / "a"), "--every", "2"]) == 2
    assert capsys.readouterr().err.startswith("error: --every: applies to recordings only")
    assert main(["depth", str(profile), "--left-dir", str(folder / "left"), "--right-dir", str(folder / "right"),
                 "-o", str(tmp_path / "b"), "--max-frames", "1"]) == 2
    assert capsys.readouterr().err.startswith("error: --max-frames: applies to recordings only")
    for bad in ("bad ns//", "/1st-cam", "stereo", "/a//b"):
        assert main(["depth", str(profile), str(folder), "-o", str(tmp_path / "c"), "--to", "ros2",
                     "--namespace", bad]) == 2
        assert "is not a ROS namespace" in capsys.readouterr().err
    assert main(["-q", "depth", str(profile), str(folder), "-o", str(tmp_path / "d"), "--to", "ros2",
                 "--namespace", "/robot1/front_stereo", "--max-frames", "1"]) == 0
    assert not (tmp_path / "a").exists() and not (tmp_path / "c").exists()

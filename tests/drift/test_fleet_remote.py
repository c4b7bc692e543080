"""Recordings at URLs: a fleet robot whose recording is served by `python -m http.server` on 127.0.0.1 gives the
verdict and rotation of the same recording on disk; the reader refuses redirects, oversize files, other schemes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.drift.check import CheckSettings
from s2r.drift.fleet import load_fleet, run_robot
from s2r.recordings.remote import RemoteError, copy_to, join, list_folder
from tests.drift.fleet_cluster import http_server


def test_a_recording_over_http_is_judged_as_the_same_recording_on_disk(tmp_path: Path, drift_rig_file: Path,
                                                                       recordings: dict[str, Path]) -> None:
    root = recordings["turned"].parent
    with http_server(root) as base:
        fleet = tmp_path / "fleet.yaml"
        fleet.write_text(json.dumps({"robots": [
            {"name": "web", "profile": str(drift_rig_file), "recording": f"{base}/turned/"},
            {"name": "disk", "profile": str(drift_rig_file), "recording": str(recordings["turned"])},
            {"name": "file", "profile": str(drift_rig_file),
             "recording": {"folder": recordings["turned"].as_uri(), "max_frames": 3}}]}))
        jobs = load_fleet(fleet, settings=CheckSettings(), max_frames=3)
        web, disk, file = (run_robot(job) for job in jobs)
    assert disk["verdict"] == "drifted" and web["verdict"] == disk["verdict"] == file["verdict"]
    assert web["rotation_error_deg"] == disk["rotation_error_deg"] == file["rotation_error_deg"]
    assert web["recording"]["pairs"] == disk["recording"]["pairs"] == 3  # the same 3 of 4 pairs, spread
    assert web["recording"]["sha256"] == disk["recording"]["sha256"]  # identity: the pixels, not the place
    assert web["recording"]["source"] == f"{base}/turned/"


def test_the_reader_follows_no_redirect_and_keeps_its_limits(tmp_path: Path, recordings: dict[str, Path]) -> None:
    with http_server(recordings["same"]) as base:
        names = [e.name for e in list_folder(f"{base}/left")]
        assert names == ["00.png", "01.png", "02.png", "03.png"]
        size = (recordings["same"] / "left" / "00.png").stat().st_size
        copy = copy_to(f"{base}/left/00.png", tmp_path / "a.png", limit=size)
        assert copy.read_bytes() == (recordings["same"] / "left" / "00.png").read_bytes()
        with pytest.raises(RemoteError, match="redirects to '/left/'"):  # http.server sends folders to NAME/
            copy_to(f"{base}/left", tmp_path / "b.png", limit=1 << 20)
        with pytest.raises(RemoteError, match=f"{size} bytes, over"):
            copy_to(f"{base}/left/00.png", tmp_path / "c.png", limit=size - 1)
        with pytest.raises(RemoteError, match="not found"):
            copy_to(f"{base}/left/99.png", tmp_path / "d.png", limit=1 << 20)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]  # nothing partial left behind
    with pytest.raises(RemoteError, match="not a regular file"):
        copy_to("file:///dev/zero", tmp_path / "e.png", limit=1 << 20)


@pytest.mark.parametrize("url", ["memory://r01", "ftp://127.0.0.1/r01", "simplecache::http://127.0.0.1/r01",
                                 "file://otherhost/r01"])
def test_a_recording_url_of_another_kind_is_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                      url: str) -> None:
    fleet = tmp_path / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": [{"name": "a", "profile": "p.yaml", "recording": url}]}))
    assert main(["fleet", "check", str(fleet), "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {fleet}: robots[0].recording: ") and "\n" not in err
    assert not (tmp_path / "o").exists()


def test_s3_without_the_s3fs_extra_is_named_per_robot(tmp_path: Path, drift_rig_file: Path) -> None:
    """Without s3fs nothing is contacted: the robot fails with the one line saying what to install."""
    import importlib.util

    if importlib.util.find_spec("s3fs") is not None:
        pytest.skip("s3fs is installed: this would contact S3, and nothing but loopback is contacted in tests")
    fleet = tmp_path / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": [{"name": "a", "profile": str(drift_rig_file),
                                             "recording": "s3://fleet-logs/a/"}]}))
    (job,) = load_fleet(fleet, settings=CheckSettings())
    row = run_robot(job)
    assert row["verdict"] == "failed"
    assert row["reasons"] == ["s3://fleet-logs/a/: reading s3:// needs s3fs (pip install 's2r[s3]') "
                              "(install it on every worker)"]


def test_names_that_need_percent_encoding_are_listed_and_read(tmp_path: Path) -> None:
    served = tmp_path / "served" / "left"
    served.mkdir(parents=True)
    (served / "a b#1.png").write_bytes(b"12345")
    with http_server(tmp_path / "served") as base:
        (entry,) = list_folder(f"{base}/left/")
        assert entry.name == "a b#1.png"
        copy = copy_to(join(f"{base}/left/", entry.name), tmp_path / "copy.png", limit=5)
    assert copy.read_bytes() == b"12345"
    assert copy_to(join((tmp_path / "served").as_uri(), "left", "a b#1.png"), tmp_path / "c2", limit=5).read_bytes() \
        == b"12345"

"""s2r fleet check: six robots on a local two-worker Dask cluster give what separate s2r check runs give."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s2r.cli import main


def _fleet(tmp_path: Path, rig_file: Path, recordings: dict[str, Path]) -> Path:
    robots = [
        {"name": "r1", "profile": str(rig_file), "recording": str(recordings["same"])},
        {"name": "r2", "profile": str(rig_file), "recording": str(recordings["turned"])},
        {"name": "r3", "profile": str(rig_file), "recording": {"left": str(recordings["same"] / "left" / "*.png"),
                                                               "right": str(recordings["same"] / "right" / "*.png"),
                                                               "max_frames": 2}},
        {"name": "r4", "profile": str(rig_file), "recording": {"folder": str(recordings["turned"]), "max_frames": 2}},
        {"name": "broken", "profile": str(rig_file), "recording": "no_such_folder"},
        {"name": "r6", "profile": "missing_profile.yaml", "recording": str(recordings["same"])},
    ]
    path = tmp_path / "fleet.yaml"
    path.write_text(json.dumps({"robots": robots}))  # JSON is YAML
    return path


@pytest.mark.slow
def test_fleet_matches_single_checks_and_names_broken_robots(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                            drift_rig_file: Path,
                                                            recordings: dict[str, Path]) -> None:
    fleet = _fleet(tmp_path, drift_rig_file, recordings)
    out = tmp_path / "out"
    code = main(["fleet", "check", str(fleet), "-o", str(out), "--workers", "2", "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert code == 1
    rows = {r["name"]: r for r in summary["robots"]}
    assert [r["name"] for r in summary["robots"]][:2] == ["broken", "r6"]  # most severe first
    assert rows["broken"]["verdict"] == "failed" and "no_such_folder" in rows["broken"]["reasons"][0]
    assert rows["r6"]["verdict"] == "failed" and "missing_profile.yaml" in rows["r6"]["reasons"][0]
    singles = {"r1": [str(recordings["same"])], "r2": [str(recordings["turned"])],
               "r3": ["--left", str(recordings["same"] / "left" / "*.png"),
                      "--right", str(recordings["same"] / "right" / "*.png"), "--max-frames", "2"],
               "r4": [str(recordings["turned"]), "--max-frames", "2"]}
    for name, recording in singles.items():
        assert main(["check", str(drift_rig_file), *recording, "--json"]) in (0, 1)
        single = json.loads(capsys.readouterr().out)
        assert rows[name]["verdict"] == single["verdict"]
        # the same to rounding: BLAS may sum in another order in a single-threaded worker than here
        assert rows[name]["rotation_error_deg"] == pytest.approx(single["rotation_error_deg"], abs=1e-9)
        assert rows[name]["sigma_deg"] == pytest.approx(single["sigma_deg"], abs=1e-9)
        assert rows[name]["matches"] == single["matches"]
    assert rows["r1"]["verdict"] == "good" and rows["r2"]["verdict"] == "drifted"
    assert summary["counts"] == {"failed": 2, "drifted": 2, "cannot tell": 0, "good": 2}
    assert (out / "index.html").is_file() and (out / "r2" / "check.html").is_file()
    assert json.loads((out / "summary.json").read_text())["counts"]["failed"] == 2


def test_a_bad_fleet_file_is_bad_input(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "fleet.yaml"
    path.write_text("robots:\n  - name: a\n    profile: p.yaml\n")
    assert main(["fleet", "check", str(path), "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {path}: robots[0]") and "recording" in err
    entry = "  - {name: a, profile: p.yaml, recording: r}\n"
    path.write_text("robots:\n" + entry + entry)
    assert main(["fleet", "check", str(path), "-o", str(tmp_path / "o")]) == 2
    assert "repeated name" in capsys.readouterr().err

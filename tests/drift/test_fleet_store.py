"""The fleet's journal and history without running a check: hand-made rows, hand-computed trends."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.drift.fleet_store import Journal, history_entry, robot_trends, trend_summary, write_history


def _row(name: str, pitch: float, verdict: str = "good") -> dict[str, object]:
    return {"name": name, "verdict": verdict, "reasons": [], "rotation_error_deg": {"pitch": pitch, "yaw": 0.0,
            "roll": float("nan")}, "sigma_deg": {"pitch": 0.01, "yaw": 0.01, "roll": 0.01},
            "tolerance_deg": {"pitch": 0.1, "yaw": 0.1, "roll": 0.1}, "recording": {"source": "x", "pairs": 3}}


def test_the_journal_gives_back_only_rows_of_unchanged_jobs(tmp_path: Path) -> None:
    journal = Journal(tmp_path / "out")
    assert not journal.exists() and journal.finished({"a": "k1"}) == {}
    journal.add(_row("a", 0.01), "k1")
    journal.add(_row("b", 0.02), "k2")
    (journal.folder / "c.json").write_text('{"key": "k3", "row": {"na')  # torn by a crash: ignored
    rows = journal.finished({"a": "k1", "b": "changed", "c": "k3"})
    assert list(rows) == ["a"] and rows["a"]["rotation_error_deg"]["pitch"] == 0.01
    journal.remove()
    assert not journal.exists() and (tmp_path / "out").is_dir()


def test_a_trend_is_a_least_squares_rate_and_the_days_left_at_that_rate(tmp_path: Path) -> None:
    start = dt.datetime(2026, 12, 1, 2, 0, tzinfo=dt.timezone.utc)
    for day, pitch in enumerate((0.01, 0.03, 0.05)):  # 0.02 deg a day, exactly
        write_history(tmp_path, history_entry([_row("r", pitch), _row("s", 0.0)], when=start + dt.timedelta(day)))
    trends = robot_trends(tmp_path, history_entry([_row("r", 0.07)], when=start + dt.timedelta(3)))
    assert [p["rotation_error_deg"]["pitch"] for p in trends["r"]] == [0.01, 0.03, 0.05, 0.07]
    assert trends["r"][0]["rotation_error_deg"]["roll"] is None  # not estimated: no point, not a zero
    summary = trend_summary(trends["r"], {"pitch": 0.1, "yaw": 0.1, "roll": 0.1})
    assert summary["runs"] == 4
    assert summary["rate_deg_per_day"]["pitch"] == pytest.approx(0.02)
    assert summary["days_to_tolerance"]["pitch"] == pytest.approx(1.5)  # (0.1 - 0.07) / 0.02
    assert summary["rate_deg_per_day"]["yaw"] == 0.0 and summary["days_to_tolerance"]["yaw"] is None
    assert summary["rate_deg_per_day"]["roll"] is None
    assert len(trends["s"]) == 3  # not in the current run: its history still shows
    assert all(json.loads(p.read_text())["time"].endswith("+00:00") for p in tmp_path.glob("run-*.json"))


def test_a_robot_name_is_matched_whole(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fleet = tmp_path / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": [{"name": "r1\n", "profile": "p.yaml", "recording": "r"}]}))
    assert main(["fleet", "check", str(fleet), "-o", str(tmp_path / "o")]) == 2
    assert "robots[0].name: bad or repeated name" in capsys.readouterr().err


def test_resume_needs_an_interrupted_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fleet = tmp_path / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": [{"name": "r1", "profile": "p.yaml", "recording": "r"}]}))
    assert main(["fleet", "check", str(fleet), "-o", str(tmp_path / "o"), "--resume"]) == 2
    assert "holds no interrupted fleet run to resume" in capsys.readouterr().err
    Journal(tmp_path / "o").add(_row("r1", 0.0), "k")
    (tmp_path / "o" / "index.html").write_text("an earlier run")
    assert main(["fleet", "check", str(fleet), "-o", str(tmp_path / "o"), "--resume"]) == 2
    assert "holds other files (index.html)" in capsys.readouterr().err

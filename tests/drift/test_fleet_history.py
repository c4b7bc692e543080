"""--history: two nights of a fleet whose robot "creep" turns further each night (pitch 0.03 deg, then 0.07 deg;
tolerance 0.1 deg, and 5 px so that the degrees decide: good both nights) beside a steady robot; the trend shows the
creep's rate and the days left before it crosses the tolerance, in summary.json and as a plot per robot in
index.html."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import pytest

from s2r.cli import main
from tests.drift.conftest import rig, write_recording


@pytest.mark.slow
def test_two_nights_show_a_drift_that_grows_before_it_crosses_the_tolerance(
        tmp_path: Path, drift_rig_file: Path, recordings: dict[str, Path],
        capsys: pytest.CaptureFixture[str]) -> None:
    history = tmp_path / "history"
    for night, pitch in enumerate((0.03, 0.07)):
        creep = write_recording(tmp_path / f"creep{night}", rig(), (pitch, 0.0, 0.0), frames=3, seed=5 + night)
        fleet = tmp_path / f"fleet{night}.yaml"
        fleet.write_text(json.dumps({"robots": [
            {"name": "creep", "profile": str(drift_rig_file), "recording": str(creep)},
            {"name": "steady", "profile": str(drift_rig_file),
             "recording": {"folder": str(recordings["same"]), "max_frames": 3}}]}))
        out = tmp_path / f"night{night}"
        code = main(["fleet", "check", str(fleet), "-o", str(out), "--history", str(history), "--tolerance", "0.1",
                     "--tolerance-px", "5", "--workers", "1", "--json"])  # the degrees decide here, not the rows
        summary = json.loads(capsys.readouterr().out)
        assert code == 0, summary
        if night == 0:  # the first night moved a day back, as if it had run yesterday
            (run_file,) = history.glob("run-*.json")
            entry = json.loads(run_file.read_text())
            entry["time"] = (dt.datetime.fromisoformat(entry["time"]) - dt.timedelta(days=1)).isoformat()
            run_file.write_text(json.dumps(entry))
    runs = sorted(history.glob("run-*.json"))
    assert len(runs) == 2
    last = json.loads(runs[-1].read_text())
    identity = last["robots"]["creep"]["recording"]
    assert identity["pairs"] == 3 and len(identity["sha256"]) == 64 and identity["source"].endswith("creep1")
    trends = {r["name"]: r["trend"] for r in summary["robots"]}
    creep_trend, steady = trends["creep"], trends["steady"]
    assert [p["verdict"] for p in creep_trend["points"]] == ["good", "good"]
    assert creep_trend["rate_deg_per_day"]["pitch"] == pytest.approx(0.04, abs=0.015)
    assert abs(creep_trend["rate_deg_per_day"]["roll"]) < 0.015
    assert 0.3 < creep_trend["days_to_tolerance"]["pitch"] < 2.0  # (0.1 - 0.07) / 0.04 = 0.75 day
    assert steady["rate_deg_per_day"]["pitch"] == pytest.approx(0.0, abs=1e-9)  # the same pixels both nights
    assert steady["points"][0]["recording"]["sha256"] == steady["points"][1]["recording"]["sha256"]
    page = (tmp_path / "night1" / "index.html").read_text()
    assert "Trend per robot" in page and page.count("rotation error over the runs (deg)</figcaption>") == 2
    assert page.count("<img src='data:image/png;base64,") == 2

"""validate --recording: a recording rendered through a rig (known poses) measured as the real camera, the same
boards re-rendered at the recovered poses through the sim; a twin sim agrees, a different baseline shows."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from s2r.render.boards.sets import render_board_set
from s2r.validate.recording.compare import compare_recording, recording_checks
from s2r.validate.recording.report import recording_lines, recording_sections
from s2r.validate.tolerances import Tolerances
from tests.conftest import make_rig

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[np.ndarray]]:
    rig = make_rig(name="recorded_rig")
    out = tmp_path_factory.mktemp("rec")
    boards = render_board_set(rig, out, views=4, pattern=(9, 6), square_m=0.04, seed=3, supersample=1, jobs=1)
    return out, boards.poses


def test_twin_sim_agrees_and_poses_come_back(recording: tuple[Path, list[np.ndarray]]) -> None:
    folder, truth = recording
    rig = make_rig(name="recorded_rig")
    comparison = compare_recording(rig, rig, folder, pattern=(9, 6), square_m=0.04, preset="profile",
                                   tol=Tolerances())
    scored = [f for f in comparison.real.frames if f.distance_m is not None]
    assert len(scored) == len(truth) and len(comparison.sim.frames) == len(truth)
    for f, T in zip(scored, truth, strict=True):  # the board's distance comes back from PnP
        centre = T[:3, :3] @ np.array([4 * 0.04, 2.5 * 0.04, 0.0]) + T[:3, 3]
        assert f.distance_m == pytest.approx(float(centre[2]), rel=0.05)
        assert abs(f.z_accuracy_pct or 9) < 1.0
    assert comparison.rows and all(r["passed"] for r in comparison.rows), comparison.rows
    data = comparison.as_dict()
    assert {"real", "sim", "rows"} <= set(data) and data["real"]["bins"] and data["sim"]["bins"]
    assert all(c.passed for c in recording_checks(comparison))
    assert any("Recording" in line for line in recording_lines(comparison))
    assert recording_sections(comparison)[0].tables


def test_cli_refuses_a_recording_without_real(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from s2r.cli import main

    assert main(["validate", "gazebo_dual_camera", "--recording", str(tmp_path)]) == 2
    assert "SIM REAL" in capsys.readouterr().err
    assert main(["validate", "gazebo_dual_camera", "gazebo_dual_camera", "--roles-as-given", "--recording",
                 str(tmp_path / "x")]) == 2
    assert "recording folder not found" in capsys.readouterr().err

"""The matcher-range warning and its "needed" figure agree (the largest disparity is min + num - 1), and
validate prints it once, not again from its depth task."""

from __future__ import annotations

import logging

import pytest

from s2r.depth.pipeline import StereoPipeline
from s2r.registry import load_profile
from s2r.validate import tasks
from s2r.validate.settings import QUICK
from s2r.validate.tolerances import Tolerances


def test_exact_multiple_of_16_gets_one_more_step(caplog: pytest.LogCaptureFixture) -> None:
    # realsense_d435_1280x720: fx' B / z_min = 640 * 0.05 / 0.5 = 64 px exactly; 64 disparities reach only 63
    profile = load_profile("realsense_d435_1280x720")
    with caplog.at_level(logging.WARNING, logger="s2r.depth.presets"):
        pipe = StereoPipeline(profile)
    assert caplog.records == [] and pipe.config.num_disparities == 80
    assert profile.num_disparities_for() == 80 and profile.depth_range_m()[0] <= 0.5


def test_the_needed_figure_removes_the_warning(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, logger="s2r.depth.presets"):
        StereoPipeline("realsense_d435_1280x720", num_disparities=64)
    (record,) = caplog.records
    assert "with 64 disparities" in record.getMessage() and "needs num_disparities=80" in record.getMessage()
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="s2r.depth.presets"):
        StereoPipeline("realsense_d435_1280x720", num_disparities=80)
    assert caplog.records == []


def test_validate_depth_task_does_not_repeat_the_warning(monkeypatch: pytest.MonkeyPatch,
                                                         caplog: pytest.LogCaptureFixture) -> None:
    def fake_measure(profile: object, **_: object) -> str:  # builds the pipeline as measure_depth_accuracy does
        StereoPipeline(profile, preset="seed-sgbm", num_disparities=16)  # type: ignore[arg-type]
        return "measured"

    monkeypatch.setattr(tasks, "measure_depth_accuracy", fake_measure)
    profile = load_profile("realsense_d435_848x480")
    with caplog.at_level(logging.WARNING):
        assert tasks._task("depth", profile, QUICK, Tolerances()) == "measured"
    assert caplog.records == []
    assert logging.getLogger("s2r.depth.presets").level == logging.NOTSET  # restored

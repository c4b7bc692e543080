"""What a newcomer meets first: usage errors that say what to type, roles that cannot be swapped silently,
progress lines in a log, and a demo that ends with the command to run next."""

from __future__ import annotations

import io
import time
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.cli._common import ProgressBar
from s2r.cli.demo import _next_steps


def _usage_error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    return capsys.readouterr().err.strip().splitlines()[-1]


def test_a_subcommand_typo_gets_did_you_mean(capsys: pytest.CaptureFixture[str]) -> None:
    assert "did you mean 'calibrate'?" in _usage_error(capsys, ["calibrte"])
    assert "did you mean 'convert'?" in _usage_error(capsys, ["profile", "convrt"])


def test_a_mistyped_option_is_named_not_a_missing_command(capsys: pytest.CaptureFixture[str]) -> None:
    line = _usage_error(capsys, ["--verison"])
    assert "unrecognized option --verison (did you mean --version?)" in line
    assert "COMMAND" not in line


def test_optional_positionals_are_not_listed_as_required(capsys: pytest.CaptureFixture[str]) -> None:
    line = _usage_error(capsys, ["lint"])
    assert line.endswith("the following arguments are required: file")


def test_swapped_roles_are_refused_unless_asked(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", "realsense_d435_848x480", "gazebo_dual_camera", "--quick"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: SIM REAL: the roles look swapped")
    assert "s2r validate gazebo_dual_camera realsense_d435_848x480" in err and "--roles-as-given" in err
    assert main(["validate", "gazebo_dual_camera", "xbot_u_stereo", "--quick"]) == 2
    assert "REAL xbot_u_stereo is a simulated camera" in capsys.readouterr().err


def test_progress_in_a_log_prints_lines_and_a_heartbeat() -> None:
    stream = io.StringIO()  # not a terminal: log lines, not a redrawn bar
    bar = ProgressBar(stream=stream, log_every_s=0.2)
    bar(0, 4, "render")
    time.sleep(0.7)  # a stage silent for longer than log_every_s: the heartbeat repeats its state
    bar(4, 4, "render")
    lines = stream.getvalue().splitlines()
    assert any(line.startswith("progress: render 0/4 (") for line in lines)
    assert lines[-1].startswith("progress: render 4/4 (")
    assert "\r" not in stream.getvalue() and "#" not in stream.getvalue()


def test_progress_stays_silent_for_a_quick_run_and_when_disabled() -> None:
    quick, off = io.StringIO(), io.StringIO()
    bar = ProgressBar(stream=quick)  # the first 10 s print nothing: a one-line error stays one line
    bar(0, 2, "detect")
    bar(2, 2, "detect")
    ProgressBar(enabled=False, stream=off)(1, 2, "detect")
    assert quick.getvalue() == "" and off.getvalue() == ""


def test_demo_ends_with_a_command_that_runs_s2r() -> None:
    text = _next_steps()
    assert "s2r --help" in text and "activate" in text


def test_quiet_and_debug_work_after_the_subcommand_too(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "show", "gazebo_dual_camera", "-q"]) == 0
    assert main(["validate", "no_such_rig", "-q"]) == 2
    assert capsys.readouterr().err.startswith("error: ")
    with pytest.raises(Exception, match="no_such_rig"):
        main(["validate", "no_such_rig", "--debug"])


def test_the_profile_is_the_first_positional_of_sensor_fit_and_apply(capsys: pytest.CaptureFixture[str],
                                                                    tmp_path: Path) -> None:
    # the profile is read first: a missing recording is the next error either way, the alias still works
    assert main(["sensor", "fit", "realsense_d435_848x480", "--pattern", "9x6", "--square", "0.025",
                 "-o", str(tmp_path / "s.yaml")]) == 2
    assert capsys.readouterr().err.strip() == ("error: --left: missing left images (pass --left DIR|GLOB (or a "
                                               "recording))")
    assert main(["sensor", "apply", "no_such_rig", str(tmp_path / "s.yaml"), str(tmp_path), "-o",
                 str(tmp_path / "out")]) == 2
    assert "no_such_rig" in capsys.readouterr().err
    assert main(["sensor", "apply", str(tmp_path / "s.yaml"), str(tmp_path), "--profile", "no_such_rig", "-o",
                 str(tmp_path / "out")]) == 2
    assert "no_such_rig" in capsys.readouterr().err
    assert main(["sensor", "apply", str(tmp_path / "s.yaml"), str(tmp_path), "-o", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err.strip() == ("error: PROFILE: missing the profile (give it first: s2r sensor "
                                               "apply PROFILE ... (a name or a YAML path))")


@pytest.mark.parametrize("command", [["validate"], ["depth-quality"], ["sensor", "fit"], ["sensor", "apply"]])
def test_reversed_arguments_get_a_one_line_hint(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                command: list[str]) -> None:
    (tmp_path / "run1").mkdir()
    assert main([*command, str(tmp_path / "run1"), "realsense_d435_848x480", "-o", str(tmp_path / "x")]) == 2
    assert capsys.readouterr().err == (
        f"error: {tmp_path / 'run1'} is a folder and realsense_d435_848x480 a profile: arguments reversed? the profile "
        f"comes first: s2r {' '.join(command)} realsense_d435_848x480 ...\n")


def test_a_recording_file_first_is_reversed_too_but_two_recordings_are_not(capsys: pytest.CaptureFixture[str],
                                                                           tmp_path: Path) -> None:
    (tmp_path / "run.bag").write_bytes(b"")
    assert main(["-q", "validate", str(tmp_path / "run.bag"), "realsense_d435_848x480"]) == 2
    assert "arguments reversed? the profile comes first: s2r validate realsense_d435_848x480 ..." in \
        capsys.readouterr().err
    (tmp_path / "d").mkdir()
    assert main(["sensor", "apply", str(tmp_path / "d"), str(tmp_path / "d"), "-o", str(tmp_path / "o")]) == 2
    assert "reversed" not in capsys.readouterr().err


def test_a_fleet_sized_stage_logs_each_robot_as_it_finishes() -> None:
    stream = io.StringIO()
    bar = ProgressBar(stream=stream, log_every_s=0.2)
    bar(0, 5, "checking robots")
    time.sleep(0.25)  # past the quiet start
    bar(1, 5, "checking robots")  # the first robot done is a line at once, not a heartbeat later
    bar(2, 5, "checking robots")
    lines = [line.split(" (")[0] for line in stream.getvalue().splitlines()]
    assert lines[-2:] == ["progress: checking robots 1/5", "progress: checking robots 2/5"]

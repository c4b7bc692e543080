"""One name per option across commands: ``--jobs`` for parallelism (``--workers`` a hidden alias that still works),
and ``s2r check --profile P FOLDER`` as depth and sensor take it, giving the same result as ``check P FOLDER``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from s2r.cli import build_parser, main
from tests.drift.conftest import rig, write_recording

#: One run of every command that takes --jobs (OUT: the test folder, IN: an empty input folder in it).
EVERY_JOBS_COMMAND = [
    ["depth", "realsense_d435_848x480", "a.png", "b.png", "-o", "OUT/o"],
    ["calibrate", "IN", "--pattern", "9x6", "--square", "0.025", "-o", "OUT/c.yaml"],
    ["check", "realsense_d435_848x480", "IN"],
    ["render", "boards", "realsense_d435_848x480", "-o", "OUT/b"],
    ["render", "scene", "realsense_d435_848x480", "-o", "OUT/s"],
    ["validate", "realsense_d435_848x480", "realsense_d435_848x480"],
    ["fleet", "check", "IN/fleet.yaml", "-o", "OUT/f"],
]


def _subparser(parser: argparse.ArgumentParser, *path: str) -> argparse.ArgumentParser:
    for name in path:
        action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = action.choices[name]
    return parser


@pytest.mark.parametrize("command", [("depth",), ("calibrate",), ("render", "boards"), ("render", "scene"),
                                     ("validate",), ("check",), ("fleet", "check")])
def test_parallelism_is_jobs_everywhere_and_workers_is_hidden(command: tuple[str, ...]) -> None:
    sub = _subparser(build_parser(), *command)
    options = {s for a in sub._actions if a.help != argparse.SUPPRESS for s in a.option_strings}
    assert "--jobs" in options and "--workers" not in options
    assert "--workers" not in sub.format_help()


@pytest.mark.parametrize("name", ["--jobs", "--workers"])
def test_depth_and_fleet_take_jobs_and_the_workers_alias(name: str) -> None:
    parser = build_parser()
    args = parser.parse_args(["depth", "p", "l.png", "r.png", "-o", "out", name, "3"])
    assert args.jobs == 3 and not hasattr(args, "workers")
    assert parser.parse_args(["depth", "p", "l.png", "r.png", "-o", "out"]).jobs == 2
    assert parser.parse_args(["fleet", "check", "f.yaml", "-o", "o", name, "1"]).jobs == 1


@pytest.mark.parametrize("name", ["--jobs", "--workers"])
def test_a_bad_job_count_names_both_spellings(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["depth", "realsense_d435_848x480", "a.png", "b.png", "-o", str(tmp_path / "o"), name, "0"]) == 2
    assert "--jobs/--workers: must be at least 1, got 0" in capsys.readouterr().err


@pytest.mark.parametrize("argv", EVERY_JOBS_COMMAND)
def test_every_command_refuses_a_bad_job_count_in_the_same_words(argv: list[str], tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "IN").mkdir()
    argv = [a.replace("OUT", str(tmp_path)).replace("IN", str(tmp_path / "IN")) for a in argv]
    assert main([*argv, "--jobs", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --jobs/--workers: must be at least 1, got 0 (e.g. --jobs 2)")
    assert "Traceback" not in err
    assert not any((tmp_path / n).exists() for n in ("o", "c.yaml", "b", "s", "f"))


def test_check_takes_profile_as_an_option(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from s2r.formats.s2r_yaml import dump_profile

    profile = tmp_path / "rig.yaml"
    dump_profile(rig(), profile)
    folder = write_recording(tmp_path / "rec", rig(), (0.0, 0.0, 0.0), frames=2, seed=1)
    results = []
    for argv in ([str(profile), str(folder)], ["--profile", str(profile), str(folder)],
                 [str(folder), "--profile", str(profile)], ["--profile", str(profile), "--left", str(folder / "left"),
                                                             "--right", str(folder / "right")]):
        code = main(["check", *argv, "--json", "--max-frames", "2"])
        results.append((code, json.loads(capsys.readouterr().out)["rotation_error_deg"]))
    assert all(r == results[0] for r in results[1:])
    assert main(["check", "--profile", str(profile), str(tmp_path / "other.yaml"), str(folder)]) == 2
    assert "two profiles given" in capsys.readouterr().err


@pytest.mark.parametrize("argv", EVERY_JOBS_COMMAND)
def test_every_command_refuses_more_local_workers_than_the_cores_can_hold(argv: list[str], tmp_path: Path,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    from s2r.executor import usable_cores

    (tmp_path / "IN").mkdir()
    argv = [a.replace("OUT", str(tmp_path)).replace("IN", str(tmp_path / "IN")) for a in argv]
    cores = usable_cores()
    assert main([*argv, "--jobs", str(4 * cores + 1)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: --jobs/--workers: {4 * cores + 1} local worker processes on {cores} usable cores")
    assert f"at most {4 * cores} here" in err and "Traceback" not in err


@pytest.mark.parametrize("name", ["--jobs", "--workers"])
def test_a_job_count_that_is_not_a_number_is_named(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["check", "realsense_d435_848x480", "rec", name, "abc"])
    assert exit_info.value.code == 2
    assert f"argument {name}: must be a whole number of processes, got 'abc' (e.g. --jobs 2)" in capsys.readouterr().err

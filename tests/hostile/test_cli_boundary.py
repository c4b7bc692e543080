"""Issue 14 item 8 (and issue 13 item 9): one CLI error boundary. Bad input -> exit 2 and one line; any other
exception -> exit 3 ("internal error", how to report it), traceback only with --debug; a closed pipe or Ctrl-C
ends quietly."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import pytest

from s2r import cli
from s2r.cli import EXIT_INTERNAL, main

REPO = Path(__file__).resolve().parents[2]
PROFILE = REPO / "profiles" / "real" / "realsense_d435_848x480.yaml"
#: The installed console script (``s2r.cli:entry``, which skips the interpreter's teardown) beside ``-m s2r``.
SCRIPT = Path(sys.executable).parent / "s2r"
LAUNCHERS = [pytest.param([sys.executable, "-m", "s2r"], id="python-m"),
             pytest.param([str(SCRIPT)], id="console-script",
                          marks=pytest.mark.skipif(not SCRIPT.exists(), reason=f"{SCRIPT} is not installed"))]


def _raising(exc: BaseException) -> object:
    def func(args: argparse.Namespace) -> int:
        raise exc

    return func


def _patch_show(monkeypatch: pytest.MonkeyPatch, exc: BaseException) -> None:
    real = cli.build_parser

    def build() -> argparse.ArgumentParser:
        parser = real()
        parser.set_defaults(func=_raising(exc))
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        for choice in sub.choices.values():
            choice.set_defaults(func=_raising(exc))
            for inner in choice._actions:
                if isinstance(inner, argparse._SubParsersAction):
                    for leaf in inner.choices.values():
                        leaf.set_defaults(func=_raising(exc))
        return parser

    monkeypatch.setattr(cli, "build_parser", build)


def test_unexpected_exception_is_an_internal_error_with_code_3(monkeypatch: pytest.MonkeyPatch,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    _patch_show(monkeypatch, ZeroDivisionError("float division by zero"))
    assert main(["profile", "list"]) == EXIT_INTERNAL == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: internal error (ZeroDivisionError")
    assert "--debug" in err and "report" in err and "Traceback" not in err
    with pytest.raises(ZeroDivisionError):
        main(["--debug", "profile", "list"])


def test_missing_file_is_bad_input(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    _patch_show(monkeypatch, FileNotFoundError(2, "No such file or directory", "/no/such/file"))
    assert main(["profile", "list"]) == 2
    assert capsys.readouterr().err == "error: /no/such/file: No such file or directory\n"


def test_keyboard_interrupt_is_130_and_quiet(monkeypatch: pytest.MonkeyPatch,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    _patch_show(monkeypatch, KeyboardInterrupt())
    assert main(["profile", "list"]) == 130
    assert "Traceback" not in capsys.readouterr().err


@pytest.mark.parametrize("launcher", LAUNCHERS)
@pytest.mark.parametrize("argv", [["profile", "show", str(PROFILE), "--json"], ["profile", "list"]])
def test_closed_pipe_is_quiet(launcher: list[str], argv: list[str]) -> None:
    """The reader of stdout is gone before s2r writes (``s2r ... | true``): no traceback, exit 0."""
    proc = subprocess.Popen([*launcher, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 0, err
    assert err == ""


@pytest.mark.parametrize("launcher", LAUNCHERS)
def test_piped_into_head(launcher: list[str]) -> None:
    shell = f"{' '.join(launcher)} profile show {PROFILE} --json | head -n 2"
    result = subprocess.run(["bash", "-o", "pipefail", "-c", shell], capture_output=True, text=True, timeout=120)
    assert result.stdout.count("\n") == 2 and "Traceback" not in result.stderr and result.returncode == 0



@pytest.mark.parametrize("launcher", LAUNCHERS)
def test_every_line_arrives_and_the_exit_code_is_kept(launcher: list[str], tmp_path: Path) -> None:
    """Output to a file (block-buffered) is flushed whole before the process ends, the exit code is main()'s,
    and an error is still one line on stderr with exit 2."""
    whole = subprocess.run([*launcher, "profile", "show", str(PROFILE), "--json"], capture_output=True,
                           text=True, timeout=120)
    again = subprocess.run([sys.executable, "-m", "s2r", "profile", "show", str(PROFILE), "--json"],
                           capture_output=True, text=True, timeout=120)
    assert whole.returncode == 0 and whole.stdout == again.stdout and whole.stdout.rstrip().endswith("}")
    bad = subprocess.run([*launcher, "profile", "show", str(tmp_path / "missing.yaml")], capture_output=True,
                         text=True, timeout=120)
    assert bad.returncode == 2 and bad.stdout == ""
    assert bad.stderr.count("\n") == 1 and bad.stderr.startswith("error:") and "missing.yaml" in bad.stderr

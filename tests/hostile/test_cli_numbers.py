"""Numbers on the command line that are not numbers a user means (nan, inf, 1e308, a billion views): each is one
exit-2 line naming the option, before any work starts (measured before: `--square 1e308` printed numpy overflow
warnings, `--max-error nan` and `--depth-scale nan` were accepted, `render boards --views 1000000000` rendered
until killed)."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli import main


@pytest.mark.parametrize(("argv", "option"), [
    (["calibrate", "{data}", "--pattern", "9x6", "--square", "1e308", "-o", "{out}/p.yaml"], "--square"),
    (["calibrate", "{data}", "--pattern", "9x6", "--square", "0.025", "--max-error", "nan", "-o", "{out}/p.yaml"],
     "--max-error"),
    (["calibrate", "{data}", "--pattern", "9x6", "--square", "0.025", "--max-dt", "inf", "-o", "{out}/p.yaml"],
     "--max-dt"),
    (["render", "boards", "realsense_d435_848x480", "--views", "1000000000", "-o", "{out}/r"], "views"),
    (["depth-quality", "realsense_d435_848x480", "--wall", "--depth", "{data}", "--depth-scale", "nan"],
     "--depth-scale"),
    (["depth-quality", "realsense_d435_848x480", "--wall", "--depth", "{data}", "--max-dt", "nan"], "--max-dt"),
])
def test_absurd_numbers_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str],
                                    option: str) -> None:
    data = tmp_path  # the options are checked before any input is read
    code = main([a.format(data=data, out=tmp_path) for a in argv])
    err = capsys.readouterr().err
    assert code == 2, err
    assert option in err and "Traceback" not in err and "Warning" not in err
    assert len(err.strip().splitlines()) == 1

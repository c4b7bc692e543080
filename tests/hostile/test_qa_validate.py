"""QA: ``s2r validate`` options a newcomer may get wrong are refused in one line (exit 2), not exit 3."""

from __future__ import annotations

import pytest

from s2r.cli import main


def test_negative_seed_is_bad_input(capsys: pytest.CaptureFixture[str]) -> None:
    # numpy's default_rng raised ValueError deep inside the run: "internal error", exit 3
    assert main(["validate", "realsense_d435_848x480", "--quick", "--seed", "-1"]) == 2
    assert capsys.readouterr().err.strip() == "error: --seed: must be 0 or more, got -1 (e.g. 0)"

"""Every attribute of an MJCF stereo rig set to odd values, through the CLI: ``lint`` and ``profile
from-description`` exit 0, 1 or 2 with at most one ``error:`` line and no traceback, agree on what is refused, and
write nothing when they refuse."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s2r.cli import main
from tests.hostile.test_fuzz import MJCF_RIG

ODD = ["", "nan", "1e308", "-1", "0 0 0 0", "2199023255552"]
_ATTR = re.compile(r'(\w+)="[^"]*"')


def _mutate(index: int, value: str) -> str:
    seen = iter(range(10**6))
    return _ATTR.sub(lambda m: f'{m.group(1)}="{value}"' if next(seen) == index else m.group(0), MJCF_RIG)


@pytest.mark.parametrize("index", range(len(_ATTR.findall(MJCF_RIG))))
def test_odd_attribute_values(index: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for value in ODD:
        path = tmp_path / "scene.xml"
        path.write_text(_mutate(index, value), encoding="utf-8")
        out = tmp_path / "sim.yaml"
        made = main(["profile", "from-description", str(path), "-o", str(out), "--force"])
        made_err = capsys.readouterr().err
        linted = main(["lint", str(path)])
        lint_out = capsys.readouterr()
        for code, err in ((made, made_err), (linted, lint_out.err)):
            assert code in (0, 1, 2) and "Traceback" not in err and err.count("error:") <= 1, (value, err)
        assert made in (0, 2)
        assert (made == 0) == out.exists(), (value, made_err)
        if linted == 2:
            assert made == 2, (value, lint_out.err, made_err)  # lint refuses => from-description refuses
        if made == 2 and linted != 2:
            assert linted == 1 and " error [" in lint_out.out, (value, made_err, lint_out.out)
        out.unlink(missing_ok=True)

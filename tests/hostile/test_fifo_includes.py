"""An include that exists but is no regular file (a FIFO, a device) is named as such, never opened (a FIFO would
block) and never reported as missing (before: ``included file 'pipe.xml' not found`` for a FIFO right there)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.hostile._limits import run_s2r

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs (POSIX)")

_MJCF = '<mujoco><include file="pipe.xml"/><worldbody><body><camera name="c"/></body></worldbody></mujoco>'
_SDF = '<sdf version="1.9"><world name="w"><include><uri>pipe.xml</uri></include></world></sdf>'


@pytest.mark.parametrize(("name", "text"), [("scene.xml", _MJCF), ("world.sdf", _SDF)])
def test_a_fifo_include_is_named_a_fifo_at_once(tmp_path: Path, name: str, text: str) -> None:
    os.mkfifo(tmp_path / "pipe.xml")
    (tmp_path / name).write_text(text)
    done = run_s2r("profile", "from-description", str(tmp_path / name), "-o", str(tmp_path / "p.yaml"),
                   timeout_s=30)  # a blocking open of the FIFO raises TimeoutExpired: the test fails, not hangs
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and name in lines[0], done.stderr
    assert "include 'pipe.xml' is a FIFO, not a regular file (give a file)" in lines[0]
    assert "not found" not in lines[0] and not (tmp_path / "p.yaml").exists()


def test_a_folder_mjcf_include_is_named_a_folder(tmp_path: Path) -> None:
    (tmp_path / "pipe.xml").mkdir()  # MJCF includes are files: no model folder as in SDF
    (tmp_path / "scene.xml").write_text(_MJCF)
    done = run_s2r("profile", "from-description", str(tmp_path / "scene.xml"), "-o", str(tmp_path / "p.yaml"),
                   timeout_s=30)
    assert done.returncode == 2, done.stderr
    assert "include 'pipe.xml' is a folder, not a regular file (give a file)" in done.stderr, done.stderr


def test_a_fifo_world_asset_is_named_a_fifo(tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    os.mkfifo(tmp_path / "pipe.png")
    world = tmp_path / "w.xml"
    world.write_text('<mujoco><asset><texture name="t" type="2d" file="pipe.png"/></asset><worldbody>'
                     '<body pos="0 0 1"><camera name="c"/></body></worldbody></mujoco>')
    from s2r.errors import RenderError
    from s2r.render.mujoco.world import read_world

    with pytest.raises(RenderError, match=r"file 'pipe.png' is a FIFO, not a regular file") as caught:
        read_world(str(world))
    assert caught.value.hint == "give a file"

"""Issue 37 classes 8-11: ``render --world`` on hostile MJCF worlds, each a bounded child (4 GB of address space:
EGL maps about 1 GB; a timeout: a FIFO include hung for ever) with its control cases: a world with a mesh and a
texture in subfolders (``meshdir`` / ``texturedir``) that reads and compiles, and a world that renders. The world
is read before the GL probe, so classes 8-10 need MuJoCo but no GL; class 11 compiles the world."""

from __future__ import annotations

import os
import subprocess
import zlib
from pathlib import Path

import pytest

from tests.hostile._limits import run_s2r

pytest.importorskip("mujoco")

REPO = Path(__file__).resolve().parents[2]
PROFILE = REPO / "profiles" / "sim" / "gazebo_dual_camera.yaml"
_GL_CAP = 4 << 30
_FLOOR = '<geom type="plane" size="5 5 0.1"/>'


def _gl_reason() -> str | None:
    from s2r.render.mujoco.backend import gl_unavailable_reason

    return gl_unavailable_reason()


needs_gl = pytest.mark.skipif(_gl_reason() is not None, reason="MuJoCo cannot render offscreen here")


def _world(folder: Path, name: str, body: str, *, asset: str = "", camera: str = "0 0 1") -> Path:
    folder.mkdir(exist_ok=True)
    path = folder / name
    path.write_text(f'<mujoco><asset>{asset}</asset><worldbody>{_FLOOR}{body}'
                    f'<body pos="{camera}"><camera name="c" xyaxes="0 -1 0 0 0 1"/></body></worldbody></mujoco>')
    return path


def _render(tmp_path: Path, world: Path, *camera: str) -> subprocess.CompletedProcess[str]:
    return run_s2r("render", "scene", str(PROFILE), "--renderer", "mujoco", "--world", str(world), *camera,
                   "--distances", "1", "-o", str(tmp_path / "out"), memory_bytes=_GL_CAP, timeout_s=90)


def _refused(tmp_path: Path, done: subprocess.CompletedProcess[str], *fragments: str) -> None:
    err = done.stderr
    assert done.returncode == 2, err
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    assert all(f in err for f in fragments), err
    assert not (tmp_path / "out").exists()


def _png(path: Path, side: int) -> Path:
    """An RGB PNG of side x side zeros (zlib only, fastest level): 5 MB for 20000^2."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return len(data).to_bytes(4, "big") + kind + data + (zlib.crc32(kind + data) & 0xFFFFFFFF).to_bytes(4, "big")

    packer = zlib.compressobj(1)
    row = b"\x00" * (1 + 3 * side)
    data = b"".join(packer.compress(row) for _ in range(side)) + packer.flush()
    ihdr = side.to_bytes(4, "big") * 2 + bytes([8, 2, 0, 0, 0])
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", data) + chunk(b"IEND", b""))
    return path


_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def test_control_world_with_assets_in_subfolders_reads_and_compiles(tmp_path: Path) -> None:
    """meshdir / texturedir honoured, every file handed over in memory: MuJoCo compiles it from another folder."""
    import mujoco

    from s2r.render.mujoco.world import read_world

    scene = tmp_path / "scene"
    (scene / "meshes").mkdir(parents=True)
    (scene / "tex").mkdir()
    (scene / "meshes" / "tet.obj").write_text(_OBJ)
    _png(scene / "tex" / "t.png", 64)
    (scene / "part.xml").write_text('<mujoco><worldbody><geom type="mesh" mesh="tet" material="m"/></worldbody>'
                                    '</mujoco>')
    world = scene / "w.xml"
    world.write_text('<mujoco><compiler meshdir="meshes" texturedir="tex"/><asset><mesh name="tet" file="tet.obj"/>'
                     '<texture name="t" type="2d" file="t.png"/><material name="m" texture="t"/></asset>'
                     '<include file="part.xml"/></mujoco>')
    read = read_world(str(world))
    assert sorted(read.assets) == ["s2r_asset_0.obj", "s2r_asset_1.png"] and "meshdir" not in read.xml
    os.chdir(tmp_path)  # nothing is looked up relative to the working folder
    model = mujoco.MjSpec.from_string(read.xml, assets=read.assets).compile()
    assert model.nmesh == 1 and model.ntex == 1 and int(model.tex_width[0]) == 64
    assert [p.name for p in read.files] == ["part.xml", "tet.obj", "t.png"]


@needs_gl
def test_control_world_renders(tmp_path: Path) -> None:
    done = _render(tmp_path, _world(tmp_path / "scene", "w.xml", ""), "--world-camera", "c")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out" / "depth" / "00.npy").exists()


def test_class_8_a_fifo_include_answers_at_once(tmp_path: Path) -> None:
    (tmp_path / "scene").mkdir()
    os.mkfifo(tmp_path / "scene" / "pipe.xml")
    world = _world(tmp_path / "scene", "w.xml", "")
    world.write_text(world.read_text().replace("<worldbody>", '<include file="pipe.xml"/><worldbody>'))
    _refused(tmp_path, _render(tmp_path, world), "pipe.xml", "<include> line 1")


@pytest.mark.parametrize(("asset", "fragment"), [
    ('<texture name="t" type="2d" builtin="checker" width="30000" height="30000"/>', "900000000 texture pixels"),
    ('<texture name="t" builtin="gradient" width="12000" height="12000"/>', "texture pixels"),  # a cube: 6 faces
    ('<texture name="t" type="2d" file="big.png"/>', "400000000 texture pixels"),
    ('<hfield name="h" nrow="100000" ncol="100000" size="1 1 1 1"/>', "height-field samples"),
    ('</asset><worldbody><replicate count="1000" offset="0.01 0 0"><replicate count="1000" offset="0 0.01 0">'
     '<geom size="0.001"/></replicate></replicate></worldbody><asset>', "more than 100000 elements"),
])
def test_class_9_textures_and_height_fields_are_bounded_before_mujoco(tmp_path: Path, asset: str,
                                                                     fragment: str) -> None:
    (tmp_path / "scene").mkdir()
    if "big.png" in asset:
        _png(tmp_path / "scene" / "big.png", 20000)
    _refused(tmp_path, _render(tmp_path, _world(tmp_path / "scene", "w.xml", "", asset=asset)), fragment)


@pytest.mark.parametrize("body", ['<include file="../outside.xml"/>', "ASSET:/etc/hostname",
                                  "ASSET:../outside.png", "LINK"])
def test_class_10_reads_stay_inside_the_scene_folder(tmp_path: Path, body: str) -> None:
    (tmp_path / "outside.xml").write_text(f"<mujoco><worldbody>{_FLOOR}</worldbody></mujoco>")
    _png(tmp_path / "outside.png", 8)
    (tmp_path / "scene").mkdir()
    asset = ""
    if body.startswith("ASSET:"):
        asset, body = f'<texture name="t" type="2d" file="{body[6:]}"/>', ""
    elif body == "LINK":
        (tmp_path / "scene" / "inside.png").symlink_to(tmp_path / "outside.png")
        asset, body = '<texture name="t" type="2d" file="inside.png"/>', ""
    _refused(tmp_path, _render(tmp_path, _world(tmp_path / "scene", "w.xml", body, asset=asset)), "outside")


@needs_gl
@pytest.mark.parametrize(("camera", "fragment"), [("1e308 0 0", "not a finite position"),
                                                  ("20000 0 0", "within 10000 m"), ("nan 0 0", "")])
def test_class_11_world_camera_poses_are_finite_and_sane(tmp_path: Path, camera: str, fragment: str) -> None:
    world = _world(tmp_path / "scene", "w.xml", "", camera=camera)
    _refused(tmp_path, _render(tmp_path, world, "--world-camera", "c"), "--world", fragment)

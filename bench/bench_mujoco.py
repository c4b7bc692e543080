"""Corner accuracy and speed of the two renderers: the same chessboard views drawn through one profile (fx != fy,
off-centre principal points) by PyBullet and by MuJoCo (s2r's backends, 1x and 2x supersampling) and by MuJoCo
directly through an ``export-mujoco`` file (the anchor: MuJoCo's own renderer, no s2r code in the loop), corners
found by plain OpenCV (findChessboardCorners + cornerSubPix 5x5) and compared with the known projection.

Run: ``.venv/bin/python bench/bench_mujoco.py`` (needs the mujoco extra and an EGL or OSMesa context). Prints;
asserts nothing. Times are wall seconds for the whole set on this machine, side by side in one run.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from s2r.lens.distortion import project_points
from s2r.render import render_board_set
from s2r.render.backend import RendererChoice
from s2r.sources.export.mujoco import export_mujoco
from tests.render import mujoco_direct as md
from tests.render._helpers import detect
from tests.render.test_mujoco import _rig

VIEWS = 12


def _errors(rig: object, poses: list[np.ndarray], left: list[Path], right: list[Path],
            grid: np.ndarray, pattern: tuple[int, int]) -> np.ndarray:
    profile: object = rig
    errors = []
    for k, T in enumerate(poses):
        for cam, R, t, paths in ((profile.left, np.eye(3), np.zeros(3), left),  # type: ignore[attr-defined]
                                 (profile.right, profile.R, profile.T, right)):  # type: ignore[attr-defined]
            found = detect(paths[k], pattern)
            if found is None:
                continue
            uv = project_points(cam, (grid @ T[:3, :3].T + T[:3, 3]) @ R.T + t)
            _, idx = cKDTree(found).query(uv)
            errors.append(found[idx] - uv)
    return np.concatenate(errors)


def _line(label: str, e: np.ndarray, seconds: float) -> str:
    n = np.linalg.norm(e, axis=1)
    return (f"{label:34s} corners {len(e):5d}  mean ({e[:, 0].mean():+.4f}, {e[:, 1].mean():+.4f}) px  "
            f"rms {np.sqrt((n ** 2).mean()):.4f}  p95 {np.percentile(n, 95):.4f}  max {n.max():.4f} px  "
            f"{seconds:5.1f} s")


def _direct(rig: object, tmp: Path) -> tuple[np.ndarray, float]:
    """MuJoCo's own renderer through export-mujoco's file; truth from the board poses in the left optical frame."""
    import mujoco

    text, _ = export_mujoco(rig, body="rig")  # type: ignore[arg-type]
    (tmp / "cams.xml").write_text(text)
    size = md.board_png(tmp / "board.png")
    (tmp / "scene.xml").write_text(md.scene_xml('<include file="cams.xml"/>', tmp / "board.png", size,
                                                width=640, height=480))
    start = time.perf_counter()
    md.render_views(tmp / "scene.xml", tmp / "set", left="rig_left", right="rig_right", views=VIEWS, seed=3,
                    size_m=size)
    seconds = time.perf_counter() - start
    model = mujoco.MjModel.from_xml_path(str(tmp / "scene.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    _, R_left, p_left = md._camera(model, data, "rig_left")
    poses = []
    for pos, R in md.board_poses(model, data, "rig_left", "rig_right", views=VIEWS, seed=3, size_m=size):
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R_left.T @ R, R_left.T @ (pos - p_left)
        poses.append(T)
    s = md.SQUARE_M
    grid = np.array([[(i - (md.PATTERN[0] - 1) / 2) * s, (j - (md.PATTERN[1] - 1) / 2) * s, 0.0]
                     for j in range(md.PATTERN[1]) for i in range(md.PATTERN[0])])
    n = len(poses)
    left = [tmp / "set" / "left" / f"{k:02d}.png" for k in range(n)]
    right = [tmp / "set" / "right" / f"{k:02d}.png" for k in range(n)]
    return _errors(rig, poses, left, right, grid, md.PATTERN), seconds


def main() -> None:
    from s2r.render.mujoco.backend import gl_unavailable_reason

    reason = gl_unavailable_reason()
    if reason is not None:
        print(f"skipped: MuJoCo cannot render offscreen here ({reason})")
        return
    small = _rig(320, 240)  # fx != fy, off-centre principal points; doubled to 640x480 (fx about 540 px)
    rig = small.model_copy(update={"left": small.left.scaled(640, 480), "right": small.right.scaled(640, 480)})
    grid = np.array([[i * 0.025, j * 0.025, 0.0] for j in range(6) for i in range(9)])
    print(f"{VIEWS} stereo views, 640x480, fx {rig.left.fx_px} fy {rig.left.fy_px} cx {rig.left.cx_px} "
          f"cy {rig.left.cy_px}; corner error = OpenCV corner - known projection")
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        for name, ss in (("pybullet", 1), ("pybullet", 2), ("mujoco", 1), ("mujoco", 2)):
            start = time.perf_counter()
            out = render_board_set(rig, tmp / f"{name}{ss}", views=VIEWS, seed=3, supersample=ss, jobs=1,
                                   renderer=RendererChoice(name))
            seconds = time.perf_counter() - start
            e = _errors(rig, out.poses, out.left_paths, out.right_paths, grid, (9, 6))
            print(_line(f"s2r {name} supersample {ss}", e, seconds))
        (tmp / "direct").mkdir()
        e, seconds = _direct(rig, tmp / "direct")
        print(_line("MuJoCo directly (export-mujoco)", e, seconds))


if __name__ == "__main__":
    main()

"""The pixel convention MuJoCo renders with, pinned by rendering: a small white square facing the camera, its
intensity-weighted centroid against where s2r's profile (read by ``from-description``) projects the square's centre.

Findings (MuJoCo 4.0, EGL): the optical axis renders at ``((W - 1) / 2 - px, (H - 1) / 2 - py)`` in OpenCV's 0-based
pixel-centre coordinates, ``px, py`` the principal offsets in pixels (``principalpixel``, or ``principal`` times
the pixel density); a ``fovy`` camera renders it at the exact centre. That is s2r's ``exact`` convention with the
principal offset SUBTRACTED in both axes; ``focalpixel`` "500 400" renders fx 500, fy 400 px. A square centred on
the optical axis of a camera whose principal point is a whole or half pixel renders within 0.001 px of it; squares
elsewhere (and through the right camera, placed by the profile's R and T) within 0.03 px.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import load_profile_file
from tests.sources.mjcf_oracle import FLIP, mujoco

SCENE = """<mujoco>
  <visual><headlight ambient="1 1 1" diffuse="0 0 0" specular="0 0 0"/><global offwidth="640" offheight="480"/></visual>
  <worldbody>
    <body name="head" pos="0.2 -0.1 1.0" euler="0 0 20">
      <camera name="left" pos="0 0.04 0" xyaxes="0 -1 0 0 0 1" {k}/>
      <camera name="right" pos="0 -0.04 0" xyaxes="0 -1 0 0 0 1" {k}/>
    </body>
    <body name="target" mocap="true">
      <geom type="box" size="{half} {half} 0.0005" rgba="1 1 1 1" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>"""
FORMS = {
    "fovy": 'resolution="640 480" fovy="60"',
    "principal_plus_x": 'resolution="640 480" sensorsize="0.0064 0.0048" focalpixel="500 400" principalpixel="10 0"',
    "principal_minus_x_plus_y": ('resolution="640 480" sensorsize="0.0064 0.0048" focalpixel="500 400" '
                                 'principalpixel="-20 5"'),
    "metres": 'resolution="640 480" sensorsize="0.006 0.0045" focal="0.004 0.0041" principal="0.0002 -0.0001"',
}
#: Hand-derived from MuJoCo's frustum (engine_vis_visualize.c getFrustum) for the forms above: (fx, fy, cx, cy).
HAND = {
    "principal_plus_x": (500.0, 400.0, 309.5, 239.5),
    "principal_minus_x_plus_y": (500.0, 400.0, 339.5, 234.5),
    "metres": (0.004 / 0.006 * 640, 0.0041 / 0.0045 * 480, 319.5 - 0.0002 / 0.006 * 640, 239.5 + 0.0001 / 0.0045 * 480),
}


def _renderer(model: object) -> object:
    try:
        return mujoco.Renderer(model, 480, 640)
    except Exception as exc:  # no EGL / OSMesa / display here: a skip with the reason, not a failure
        pytest.skip(f"MuJoCo cannot create an OpenGL context here ({type(exc).__name__}: {exc})")


def _centroid(image: np.ndarray) -> np.ndarray:
    weight = image.astype(np.float64).sum(axis=2)
    ys, xs = np.nonzero(weight)
    w = weight[ys, xs]
    return np.array([(xs * w).sum() / w.sum(), (ys * w).sum() / w.sum()])


def _project(K: np.ndarray, X: np.ndarray) -> np.ndarray:
    x = K @ X
    return x[:2] / x[2]


@pytest.mark.parametrize("form", list(FORMS))
def test_rendered_point_lands_where_the_profile_says(form: str, tmp_path: Path) -> None:
    path = tmp_path / "scene.xml"
    path.write_text(SCENE.format(k=FORMS[form], half="0.03"), encoding="utf-8")
    out = tmp_path / "sim.yaml"
    assert main(["profile", "from-description", str(path), "-o", str(out)]) == 0
    profile = load_profile_file(out)
    assert profile.provenance.convention == "exact"
    if form in HAND:
        got = (profile.left.fx_px, profile.left.fy_px, profile.left.cx_px, profile.left.cy_px)
        np.testing.assert_allclose(got, HAND[form], rtol=1e-6)
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    renderer = _renderer(model)
    cam = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "left")
    mujoco.mj_forward(model, data)
    R_world_left = data.cam_xmat[cam].reshape(3, 3) @ FLIP
    # the square faces the left camera turned 17 deg about its axis, so its edges cross pixels at every phase
    turn = np.radians(17.0)
    R_square = R_world_left @ np.array([[np.cos(turn), -np.sin(turn), 0], [np.sin(turn), np.cos(turn), 0], [0, 0, 1]])
    mujoco.mju_mat2Quat(data.mocap_quat[0], R_square.flatten())
    # its centre 2 m in front of the left camera: on the optical axis, then off it (x right, y down in the image)
    for offset in ((0.0, 0.0), (0.513, 0.3077), (-0.6191, -0.2533), (0.3001, -0.4117)):
        X_left = np.array([offset[0], offset[1], 2.0])
        data.mocap_pos[0] = data.cam_xpos[cam] + R_world_left @ X_left
        mujoco.mj_forward(model, data)
        X_right = profile.R @ X_left + profile.T
        for name, K, X in (("left", profile.left.K, X_left), ("right", profile.right.K, X_right)):
            renderer.update_scene(data, camera=name)
            seen = _centroid(renderer.render())
            expected = _project(K, X)
            centred = offset == (0.0, 0.0) and name == "left" and form != "metres"  # symmetric about a pixel
            tol = 1e-3 if centred else 0.05  # elsewhere the anti-aliased edges leave up to 0.03 px
            assert np.all(np.abs(seen - expected) < tol), f"{form} {name} {offset}: rendered {seen}, s2r {expected}"
    renderer.close()

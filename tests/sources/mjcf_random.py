"""Seeded random MJCF scenes for the reader-vs-MuJoCo test: body chains with every pose form, frames, both angle units,
random Euler sequences, a defaults class, and two cameras with random intrinsic forms. Shares no code with s2r."""

from __future__ import annotations

import random

__all__ = ["random_scene"]


def _n(value: float) -> str:
    return f"{value:.9g}"


def _vec(rng: random.Random, count: int, scale: float) -> str:
    return " ".join(_n(rng.uniform(-scale, scale)) for _ in range(count))


def _orientation(rng: random.Random, degree: bool) -> str:
    turn = 180.0 if degree else 3.141592653589793
    form = rng.choice(["none", "quat", "axisangle", "euler", "xyaxes", "zaxis"])
    if form == "none":
        return ""
    if form == "quat":
        return f'quat="{_vec(rng, 4, 1.0)}"'
    if form == "axisangle":
        return f'axisangle="{_vec(rng, 3, 1.0)} {_n(rng.uniform(-turn, turn))}"'
    if form == "euler":
        return f'euler="{_vec(rng, 3, turn)}"'
    if form == "xyaxes":
        return f'xyaxes="{_vec(rng, 6, 1.0)}"'
    return f'zaxis="{_vec(rng, 3, 1.0)}"'


def _intrinsics(rng: random.Random) -> str:
    width, height = rng.randint(64, 1920), rng.randint(48, 1080)
    res = f'resolution="{width} {height}"'
    form = rng.choice(["fovy", "fovy_offscreen", "focal", "focalpixel", "mixed"])
    if form == "fovy":
        return f'fovy="{_n(rng.uniform(20, 120))}" {res}'
    if form == "fovy_offscreen":
        return f'fovy="{_n(rng.uniform(20, 120))}"'
    sw, sh = rng.uniform(0.002, 0.01), rng.uniform(0.002, 0.01)
    sensor = f'sensorsize="{_n(sw)} {_n(sh)}"'
    if form == "focal":
        return (f'{sensor} focal="{_n(rng.uniform(0.5, 2) * sw)} {_n(rng.uniform(0.5, 2) * sh)}" '
                f'principal="{_n(rng.uniform(-0.1, 0.1) * sw)} {_n(rng.uniform(-0.1, 0.1) * sh)}" {res}')
    if form == "focalpixel":
        return (f'{sensor} focalpixel="{_n(rng.uniform(0.5, 2) * width)} {_n(rng.uniform(0.5, 2) * height)}" '
                f'principalpixel="{_n(rng.uniform(-30, 30))} {_n(rng.uniform(-30, 30))}" {res}')
    return (f'{sensor} focal="{_n(sw)} {_n(sh)}" focalpixel="{_n(rng.uniform(0.5, 2) * width)} 0" '
            f'principal="0 {_n(rng.uniform(-0.1, 0.1) * sh)}" principalpixel="{_n(rng.uniform(-20, 20))} 0" {res}')


def _camera(rng: random.Random, name: str, degree: bool, classed: bool) -> str:
    cls = ' class="k"' if classed else ""
    return f'<camera name="{name}"{cls} pos="{_vec(rng, 3, 0.2)}" {_orientation(rng, degree)} {_intrinsics(rng)}/>'


def random_scene(seed: int) -> str:
    """One MJCF model with cameras ``cam_a`` and ``cam_b`` somewhere in a random body chain (hinge, slide and ball
    joints with random anchors and references; a keyframe ``pose`` with random joint positions when it has joints)."""
    rng = random.Random(seed)
    degree = rng.random() < 0.5
    seq = "".join(rng.choice("xyzXYZ") for _ in range(3))
    depth = rng.randint(1, 4)
    homes = sorted(rng.randint(0, depth) for _ in range(2))
    cams = [_camera(rng, name, degree, rng.random() < 0.3) for name in ("cam_a", "cam_b")]
    head = (f'<mujoco><compiler angle="{"degree" if degree else "radian"}" eulerseq="{seq}"/>'
            f'<default><default class="k"><camera {_orientation(rng, degree)} pos="{_vec(rng, 3, 0.1)}"/>'
            f'</default></default><worldbody>')
    body, tail, qpos = "", "", []
    for level in range(depth + 1):
        body += "".join(c for c, h in zip(cams, homes, strict=True) if h == level)
        if level == depth:
            break
        frame = rng.random() < 0.4
        if frame:
            body += f'<frame pos="{_vec(rng, 3, 0.3)}" {_orientation(rng, degree)}>'
        body += f'<body name="b{level}" pos="{_vec(rng, 3, 0.5)}" {_orientation(rng, degree)}>'
        kinds: list[str] = []
        for _ in range(rng.choice([0, 0, 1, 2])):
            # MuJoCo refuses a turning joint after a ball joint in one body
            kind = rng.choice(["slide"] if "ball" in kinds else ["hinge", "slide", "ball"])
            kinds.append(kind)
            ref = f' ref="{_n(rng.uniform(-30, 30))}"' if kind != "ball" else ""
            body += f'<joint type="{kind}" axis="{_vec(rng, 3, 1.0)}" pos="{_vec(rng, 3, 0.2)}"{ref}/>'
            qpos += [_vec(rng, 4, 1.0)] if kind == "ball" else [_n(rng.uniform(-2, 2))]
        body += '<geom size="0.05"/>'
        tail = "</body>" + ("</frame>" if frame else "") + tail
    key = f'<keyframe><key name="pose" qpos="{" ".join(qpos)}"/></keyframe>' if qpos else ""
    return head + body + tail + "</worldbody>" + key + "</mujoco>"

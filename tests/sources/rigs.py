"""Small robot descriptions written for the tests (known geometry, hand-computed answers)."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"
SEED_URDF = REPO / "urdf" / "dual_camera.urdf.xacro"
FIXED_URDF = REPO / "urdf" / "dual_camera_fixed.urdf.xacro"
XBOT_SDF = REPO / "urdf" / "xbot_u_stereo.sdf"


def sensor(name: str, *, hfov: float = 1.047, width: int = 640, height: int = 480, rate: float = 30.0,
           near: float = 0.1, far: float = 100.0, extra: str = "", plugin: str = "", pose: str = "") -> str:
    """A URDF/SDF ``<sensor type="camera">`` block."""
    pose_xml = f"<pose>{pose}</pose>" if pose else ""
    return (f'<sensor type="camera" name="{name}">{pose_xml}<update_rate>{rate}</update_rate>'
            f"<camera><horizontal_fov>{hfov}</horizontal_fov><image><width>{width}</width><height>{height}</height>"
            f"</image><clip><near>{near}</near><far>{far}</far></clip>{extra}</camera>{plugin}</sensor>")


def joint(name: str, parent: str, child: str, xyz: str = "0 0 0", rpy: str = "0 0 0", kind: str = "fixed") -> str:
    """A URDF joint."""
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy}"/></joint>')


def urdf(links: list[str], joints: list[str], sensors: dict[str, str]) -> str:
    """A URDF robot with the given links, joints and ``{link: sensor xml}`` gazebo blocks (one per line)."""
    lines = ['<?xml version="1.0"?>', '<robot name="test_rig">']
    lines += [f'  <link name="{name}"/>' for name in links]
    lines += [f"  {j}" for j in joints]
    lines += [f'  <gazebo reference="{link}">{xml}</gazebo>' for link, xml in sensors.items()]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def two_camera_urdf(*, right_xyz: str = "0 -0.1 0", right_rpy: str = "0 0 0", left_sensor: str | None = None,
                    right_sensor: str | None = None) -> str:
    """left_link -> right_link at ``right_xyz``; camera sensors 'left_cam' and 'right_cam'."""
    return urdf(["left_link", "right_link"], [joint("left_to_right", "left_link", "right_link", right_xyz, right_rpy)],
                {"left_link": left_sensor or sensor("left_cam"), "right_link": right_sensor or sensor("right_cam")})


def write(tmp_path: Path, name: str, text: str) -> Path:
    """Write ``text`` to ``tmp_path / name`` and return the path."""
    path = tmp_path / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path

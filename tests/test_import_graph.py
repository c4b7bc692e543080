"""Imports run one way (DESIGN.md): a wrong-way import, or cv2/pybullet/mujoco outside their homes, fails here."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "s2r"

#: Layer of each unit -- a top-level module or subpackage, or a dotted part of one (``sensor.model``) that sits
#: in another layer than its package; a module belongs to the longest unit its dotted name starts with. A module may
#: import only from lower layers (or from its own unit). formats and sources share a layer and must not import each
#: other; so do calib, depth and render.
LAYERS: dict[str, int] = {
    "_version": 0, "errors": 0, "progress": 0, "limits": 0, "names": 0,
    "fileio": 1, "safeparse": 1, "geometry": 1, "executor": 1,  # none of these import each other
    "sensor.model": 1,  # the sensor model's type, carried by profiles
    "profile": 2, "targets": 2,
    "rectification": 3, "imageio": 3, "lens": 3,  # lens: camera and lens maths (projection, distortion, models)
    "formats": 4, "sources": 4,
    "recordings": 5,  # every input that yields stereo frames (files, bags, videos, RealSense recordings)
    "registry": 5, "htmlreport": 5, "sensor": 5,  # sensor: applies a sensor model (render uses it)
    "calib": 6, "depth": 6, "render": 6,
    "compat": 7, "quality": 7, "drift": 7,
    "validate": 8, "sensor.fit": 8,  # sensor.fit: fits a sensor model on recordings (uses quality)
    "cli": 9, "__main__": 10, "__init__": 10,
}
CV2_HOMES = {"lens", "calib", "depth", "render", "rectification", "imageio", "formats.opencv", "formats.ros",
             "validate", "quality", "drift", "sensor", "recordings"}
PYBULLET_HOMES = {"render"}
#: MuJoCo (an optional extra) is imported by one module only, lazily, when ``--renderer mujoco`` is asked for.
MUJOCO_HOMES = {"render.mujoco.backend"}


def _unit_of(dotted: str) -> str:
    """The longest unit in LAYERS that the dotted module name (without ``s2r.``) starts with."""
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in LAYERS:
            return ".".join(parts[:n])
    return parts[0]


def _unit(path: Path) -> str:
    return _unit_of(".".join(path.relative_to(PACKAGE).with_suffix("").parts))


def module_imports(path: Path) -> list[str]:
    """Absolute module names imported by the Python file at ``path`` (relative imports left out)."""
    tree = ast.parse(path.read_text())
    found: list[str] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.extend(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.append(node.module)
    return found


def _modules() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def test_every_unit_has_a_layer() -> None:
    units = {_unit(p) for p in _modules()}
    assert units <= set(LAYERS), f"add these to LAYERS: {sorted(units - set(LAYERS))}"


def test_imports_run_one_way() -> None:
    wrong = []
    for path in _modules():
        unit = _unit(path)
        for name in module_imports(path):
            if not name.startswith("s2r.") or name == "s2r":
                continue
            target = _unit_of(name.removeprefix("s2r."))
            if target == unit:
                continue
            if LAYERS[target] >= LAYERS[unit]:
                wrong.append(f"{path.relative_to(PACKAGE)} imports {name}")
    assert not wrong, "wrong-way imports:\n" + "\n".join(wrong)


def test_heavy_libraries_stay_home() -> None:
    wrong = []
    for path in _modules():
        rel = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        homes = {"cv2": CV2_HOMES, "pybullet": PYBULLET_HOMES, "mujoco": MUJOCO_HOMES}
        for name in module_imports(path):
            lib = name.split(".")[0]
            if lib in homes and not any(rel == h or rel.startswith(h + ".") for h in homes[lib]):
                wrong.append(f"{rel} imports {lib}")
    assert not wrong, "\n".join(wrong)

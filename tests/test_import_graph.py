"""Imports run one way (DESIGN.md): a wrong-way import (between units, or between the parts of a package), an import
cycle between modules, or cv2/pybullet/mujoco outside their homes, fails here. Every import counts: module-level,
deferred (inside a function) and type-only (under ``if TYPE_CHECKING:``)."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "s2r"

#: Layer of each unit -- a top-level module or subpackage, or a dotted part of one (``sensor.model``) that sits
#: in another layer than its package; a module belongs to the longest unit its dotted name starts with. A module may
#: import only from lower layers (or from its own unit). formats and sources share a layer and must not import each
#: other; so do calib, depth and render.
LAYERS: dict[str, int] = {
    "_version": 0, "errors": 0, "progress": 0, "limits": 0, "names": 0, "lazy": 0,
    "fileio": 1, "safeparse": 1, "geometry": 1, "executor": 1,  # none of these import each other
    "sensor.model": 1,  # the sensor model's type, carried by profiles
    "profile": 2, "targets": 2,
    "rectification": 3, "imageio": 3, "lens": 3,  # lens: camera and lens maths (projection, distortion, models)
    "cvpool": 3,  # the local process pool for OpenCV work
    "formats": 4, "sources": 4,
    "recordings": 5,  # every input that yields stereo frames (files, bags, videos, RealSense recordings)
    "registry": 5, "htmlreport": 5, "sensor": 5,  # sensor: applies a sensor model (render uses it)
    "calib": 6, "depth": 6, "render": 6,
    "compat": 7, "quality": 7, "drift": 7,
    "validate": 8, "sensor.fit": 8,  # sensor.fit: fits a sensor model on recordings (uses quality)
    "cli": 9, "__main__": 10, "__init__": 10,
}
CV2_HOMES = {"lens", "cvpool", "calib", "depth", "render", "rectification", "imageio", "formats.opencv", "formats.ros",
             "validate", "quality", "drift", "sensor", "recordings"}
#: Inside a package, its parts (modules and subpackages, by their first name below the package) in layers, lowest
#: first: a part may import parts of its own layer or a lower one. Every part must be listed, so a new module says
#: where it belongs. calib's stages are tests/calib/test_layout.py's.
INNER: dict[str, list[set[str]]] = {
    "fileio": [{"inputs", "reading"}, {"outputs"}, {"atomic"}],
    "executor": [{"local"}, {"runner"}],
    "profile": [{"base"}, {"camera", "settings"}, {"rig"}],
    "lens": [{"distortion", "fold", "models"}],
    "sensor": [{"model", "depth_files"}, {"depth", "files", "images"}, {"fit"}],
    "formats.realsense": [{"text"}, {"facts"}, {"bag", "db3"}, {"recording"}],
    "sources": [{"xmlparse", "isolation", "includes", "simulator", "description", "conventions", "kinematics",
                 "sensors"},  # the description model and what reading any language needs
                {"urdf", "sdf", "mjcf"},  # one subpackage per description language
                {"loader"}, {"pair_profile", "export"}, {"lint"}, {"profile_builder", "shipped"}],
    "render": [{"_pybullet", "camera", "world", "textures", "outputs", "parallel", "cubemap", "layouts"},
               {"mujoco"}, {"backend"}, {"sensor", "rig"}, {"boards"}, {"scenes"}],
    "validate": [{"tolerances", "measures"}, {"verdict", "settings"}, {"advice", "recording", "tasks"}, {"run"},
                 {"report", "summary"}],
}
#: Import cycles still known, each a set of modules: the depth package's (another branch reworks depth/; remove
#: them here once it is merged). Any other cycle fails, and so does a known one that is gone (drop it here).
KNOWN_CYCLES: list[set[str]] = [
    {"s2r.depth.outputs", "s2r.depth.pipeline", "s2r.depth.stream"},
    {"s2r.depth.writers.base", "s2r.depth.writers.files", "s2r.depth.writers.rosbag"},
]
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


def _dotted(path: Path) -> str:
    """``s2r.a.b`` of ``s2r/a/b.py`` (``s2r.a`` of ``s2r/a/__init__.py``)."""
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imported_modules(path: Path, known: set[str]) -> Iterator[str]:
    """The s2r modules the file at ``path`` imports, anywhere in it: ``from s2r.a import b`` names ``s2r.a.b`` when
    that is a module, else ``s2r.a``."""
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names if alias.name in known)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0 and node.module.startswith("s2r"):
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                yield sub if sub in known else node.module


def _import_graph() -> dict[str, set[str]]:
    paths = {_dotted(p): p for p in _modules()}
    known = set(paths)
    return {name: {m for m in _imported_modules(path, known) if m in known and m != name}
            for name, path in paths.items()}


def _cycles(graph: dict[str, set[str]]) -> list[set[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(component)
    return found


def test_no_import_cycle() -> None:
    cycles = _cycles(_import_graph())
    new = [sorted(c) for c in cycles if c not in KNOWN_CYCLES]
    gone = [sorted(c) for c in KNOWN_CYCLES if c not in cycles]
    assert not new, f"import cycles (deferred and type-only imports count): {new}"
    assert not gone, f"these cycles are gone: remove them from KNOWN_CYCLES: {gone}"


def test_cycle_finder_finds_a_cycle() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [{"a", "b", "c"}]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def _part(package: str, dotted: str) -> str | None:
    """The part of ``package`` (``validate``) that the module ``s2r.validate.measures.params`` belongs to
    (``measures``); None for the package itself or a module outside it."""
    prefix = f"s2r.{package}."
    return dotted[len(prefix):].split(".")[0] if dotted.startswith(prefix) else None


def test_every_part_of_a_layered_package_is_listed() -> None:
    missing = []
    for package, layers in INNER.items():
        listed = set().union(*layers)
        parts = {_part(package, _dotted(p)) for p in _modules()} - {None}
        missing += [f"{package}.{part}" for part in sorted(parts - listed)]
        missing += [f"{package}.{part} (listed, not found)" for part in sorted(listed - parts)]
    assert not missing, "add these to INNER (or drop them): " + ", ".join(missing)


def test_parts_of_a_package_import_one_way() -> None:
    graph = _import_graph()
    wrong = []
    for package, layers in INNER.items():
        rank = {part: i for i, layer in enumerate(layers) for part in layer}
        for module, imported in graph.items():
            part = _part(package, module)
            if part is None or part not in rank:
                continue
            for target in imported:
                other = _part(package, target)
                if other is not None and other in rank and rank[other] > rank[part]:
                    wrong.append(f"{module} imports {target} ({package}: {part} is below {other})")
    assert not wrong, "wrong-way imports inside a package:\n" + "\n".join(sorted(wrong))


#: The house rule (DESIGN.md): a module a stranger can read in one sitting. Folders stay about this size too.
MAX_MODULE_LINES = 400
MAX_MODULES_PER_FOLDER = 17  # "about 15" (issue 36); cli/ sits at 17: one command per module


def test_no_module_over_the_size_rule() -> None:
    too_long = {str(p.relative_to(PACKAGE)): n for p in PACKAGE.rglob("*.py")
                if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES}
    assert not too_long, f"modules over {MAX_MODULE_LINES} lines (split them by concern): {too_long}"


def test_no_folder_over_the_size_rule() -> None:
    crowded = {str(d.relative_to(PACKAGE.parent)): n for d in [PACKAGE, *PACKAGE.rglob("*")] if d.is_dir()
               if (n := len(list(d.glob("*.py")))) > MAX_MODULES_PER_FOLDER}
    assert not crowded, f"folders over {MAX_MODULES_PER_FOLDER} modules (group them in subpackages): {crowded}"

"""An MJCF world for ``--renderer mujoco --world SCENE.xml``, read by s2r before MuJoCo sees it.

MuJoCo's own loader (``MjSpec.from_file``) opens whatever the scene names: an include that is a FIFO hangs it, an
absolute path or ``../`` reads outside the scene's folder (``/etc/hostname``), and a texture is allocated at the size
it declares (a builtin 30000x30000 texture: 5.5 GB). Here the scene is read the way ``profile from-description``
reads an MJCF:

- **Includes** go through the same resolver and budget (:func:`s2r.sources.mjcf.include.expand_includes`): files
  inside the scene's folder only (no ``..``, absolute path or link out of it), regular files only (a FIFO or device
  is refused, never opened for blocking reads), 8 levels, 256 files, 2 MiB.
- **Assets** (every attribute ``file`` / ``file*`` of any element: meshes, textures and their cube faces, height
  fields, skins, flexcomp meshes) are resolved with the same confinement, after MuJoCo's ``meshdir`` /
  ``texturedir`` / ``assetdir`` rules, read (at most :data:`MAX_ASSET_FILES` files and :data:`MAX_ASSET_BYTES` in
  all) and handed to MuJoCo in memory under new names: MuJoCo compiles the world from that string and those bytes
  and opens no file itself. A ``<model file>`` sub-model (whose own files MuJoCo would open) is refused.
- **Sizes**: the pixels every texture declares (builtin ``width`` x ``height``, a PNG's header; x6 for cube maps)
  and every height field's samples are summed and bounded (:data:`MAX_TEXTURE_PIXELS`, :data:`MAX_HFIELD_SAMPLES`)
  before MuJoCo allocates anything, and so are the elements ``<replicate>`` expands to. What no attribute tells (a
  mesh's hull, a flexcomp's count) is bounded by compiling once in a limited child process
  (:mod:`s2r.render.mujoco.backend`).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path, PurePosixPath

from s2r.errors import RenderError, SourceError
from s2r.fileio import NotARegularFile, read_regular_file, read_text_file
from s2r.imageio import declared_size
from s2r.sources.includes import IncludeNotAFile, MissingInclude, resolve
from s2r.sources.mjcf.include import expand_includes
from s2r.sources.mjcf.pose import where
from s2r.sources.xmlparse import XmlDoc, parse_xml

__all__ = ["MAX_ASSET_BYTES", "MAX_ASSET_FILES", "MAX_HFIELD_SAMPLES", "MAX_REPLICATED_ELEMENTS",
           "MAX_TEXTURE_PIXELS", "WorldFiles", "read_world"]

#: Bytes of asset files (meshes, textures, height fields, skins) one world may read in all.
MAX_ASSET_BYTES = 256 << 20
#: Asset files one world may read.
MAX_ASSET_FILES = 1024
#: Texture pixels (all textures; a cube map counts its 6 faces) one world may declare: four 4096x4096 textures.
MAX_TEXTURE_PIXELS = 1 << 26
#: Height-field samples (all height fields) one world may declare.
MAX_HFIELD_SAMPLES = 1 << 24
#: Elements one world may hold once ``<replicate count>`` (nested: multiplied) is expanded.
MAX_REPLICATED_ELEMENTS = 100_000
_HINT = "keep the world's files inside its folder, and its textures and height fields of a usual size"
_CUBE_TYPES = ("cube", "skybox")


@dataclass
class WorldFiles:
    """A world as MuJoCo compiles it: the XML (includes expanded, asset files renamed) and the assets' bytes.

    Attributes:
        xml: the scene's MJCF text.
        assets: new asset name -> the file's bytes (``MjSpec.from_string(xml, assets=assets)``).
        path: the scene file, for messages.
        files: every file read (includes and assets), for the provenance.
    """

    xml: str
    assets: dict[str, bytes]
    path: Path
    files: list[Path] = field(default_factory=list)
    _bytes: int = 0
    _texture_px: int = 0
    _hfield_samples: int = 0


def _int_attr(doc: XmlDoc, node: ET.Element, name: str) -> int:
    text = node.get(name, "0").strip() or "0"
    try:
        value = int(text)
    except ValueError:
        raise RenderError(f"{name}={text[:40]!r} is not a whole number", path=doc.path,
                          field=where(doc, node, name)) from None
    return max(value, 0)


def _asset_dir(doc: XmlDoc, node: ET.Element) -> str:
    """MuJoCo's folder for ``node``'s files: ``texturedir`` (textures) or ``meshdir`` (the rest), else
    ``assetdir``; '' when none is set (the scene's folder)."""
    key = "texturedir" if node.tag == "texture" else "meshdir"
    value = ""
    for compiler in doc.root.iter("compiler"):
        value = compiler.get(key) or compiler.get("assetdir") or value
    return value


def _read_asset(world: WorldFiles, doc: XmlDoc, node: ET.Element, attr: str) -> bytes:
    """The bytes of the file ``node``'s ``attr`` names, confined to the scene's folder and counted."""
    name = node.get(attr, "")
    here = where(doc, node, attr)
    joined = str(PurePosixPath(_asset_dir(doc, node)) / name) if _asset_dir(doc, node) else name
    try:
        path = resolve(joined, including_file=doc.path, roots=[doc.path.parent], field=here, folders=False)
    except MissingInclude:
        raise RenderError(f"file {name[:200]!r} not found", path=doc.path, field=here,
                          hint="fix the path (relative to the scene's folder, after meshdir/texturedir)") from None
    except IncludeNotAFile as exc:  # a FIFO or device: never opened
        raise RenderError(exc.message.replace("include ", "file ", 1), path=doc.path, field=here,
                          hint="give a file") from None
    except SourceError as exc:  # outside the scene's folder: the resolver's words, for a file, not an include
        raise RenderError(exc.message.replace("include ", "file ", 1), path=doc.path, field=here,
                          hint="keep the world's files inside its folder") from None
    if len(world.files) >= MAX_ASSET_FILES:
        raise RenderError(f"the world names more than {MAX_ASSET_FILES} asset files", path=doc.path, field=here,
                          hint=_HINT)
    try:
        data = read_regular_file(path, limit=max(MAX_ASSET_BYTES - world._bytes, 0))
    except NotARegularFile as exc:
        raise RenderError(f"asset {name[:200]!r}: {exc}", path=doc.path, field=here,
                          hint=f"the assets of one world may hold {MAX_ASSET_BYTES >> 20} MiB in all") from None
    except OSError as exc:
        raise RenderError(f"cannot read asset {name[:200]!r}: {exc.strerror or exc}", path=doc.path,
                          field=here) from None
    world._bytes += len(data)
    world.files.append(path)
    return data


def _count(world: WorldFiles, doc: XmlDoc, node: ET.Element, attr: str, amount: int) -> None:
    """Add ``amount`` texture pixels or height-field samples; RenderError past the bound."""
    if node.tag == "hfield":
        world._hfield_samples += amount
        total, limit, what = world._hfield_samples, MAX_HFIELD_SAMPLES, "height-field samples"
    else:
        world._texture_px += amount
        total, limit, what = world._texture_px, MAX_TEXTURE_PIXELS, "texture pixels"
    if total > limit:
        raise RenderError(f"the world's textures declare {total} {what} (this one {amount}); s2r renders worlds of "
                          f"at most {limit}", path=doc.path, field=where(doc, node, attr), hint=_HINT)


def _check_sizes(world: WorldFiles, doc: XmlDoc, node: ET.Element) -> None:
    """Count what ``node`` declares without a file: a builtin texture's pixels, a height field's samples."""
    if node.tag == "texture" and node.get("builtin", "none") != "none":
        w, h = _int_attr(doc, node, "width"), _int_attr(doc, node, "height")
        cube = node.get("type", "cube") in _CUBE_TYPES  # six faces of width x width (height at most)
        _count(world, doc, node, "width", 6 * w * max(w, h) if cube else w * h)
    elif node.tag == "hfield" and "file" not in node.attrib:
        _count(world, doc, node, "nrow", _int_attr(doc, node, "nrow") * _int_attr(doc, node, "ncol"))


def _take_files(world: WorldFiles, doc: XmlDoc, node: ET.Element) -> None:
    """Read every file attribute of ``node`` into ``world.assets`` under a new name, and count its size."""
    for attr in [a for a in node.attrib if a.startswith("file")]:
        if node.tag == "model":
            raise RenderError("a <model file> sub-model is not read with --world (MuJoCo would open its files)",
                              path=doc.path, field=where(doc, node, attr), hint="copy its elements into the scene")
        data = _read_asset(world, doc, node, attr)
        size = declared_size(data)
        if size is not None and node.tag in ("texture", "hfield"):
            _count(world, doc, node, attr, size[0] * size[1])
        key = f"s2r_asset_{len(world.assets)}{PurePosixPath(node.get(attr, '')).suffix.lower()}"
        world.assets[key] = data
        node.set(attr, key)


def _check_replicates(doc: XmlDoc) -> None:
    """Refuse a world whose ``<replicate>`` counts (multiplied when nested) expand past
    :data:`MAX_REPLICATED_ELEMENTS` elements (1000 x 1000 geoms: minutes of compiling)."""
    total = 0
    stack: list[tuple[ET.Element, int]] = [(doc.root, 1)]
    while stack:
        node, factor = stack.pop()
        total += factor
        if total > MAX_REPLICATED_ELEMENTS:
            raise RenderError(f"the world expands to more than {MAX_REPLICATED_ELEMENTS} elements (<replicate> "
                              "counts multiply)", path=doc.path, field=where(doc, node), hint=_HINT)
        inner = factor * max(_int_attr(doc, node, "count"), 1) if node.tag == "replicate" else factor
        stack.extend((child, inner) for child in node)


@lru_cache(maxsize=4)
def read_world(scene_path: str) -> WorldFiles:
    """The world ``scene_path`` as MuJoCo should compile it (module docstring), read once per process.

    Raises:
        SourceError: an include outside the scene's folder, missing, a FIFO or device, or past the budget.
        RenderError: the same for an asset file, or textures / height fields past their bounds.
    """
    path = Path(scene_path)
    doc = parse_xml(read_text_file(path, error=RenderError), path)
    if doc.root.tag != "mujoco":
        raise RenderError(f"expected a <mujoco> root element, got <{str(doc.root.tag)[:40]}>", path=path,
                          field="--world", hint="pass an MJCF world")
    world = WorldFiles(xml="", assets={}, path=path, files=expand_includes(doc))
    _check_replicates(doc)
    for node in doc.root.iter():
        _check_sizes(world, doc, node)
        _take_files(world, doc, node)
    for compiler in doc.root.iter("compiler"):
        for key in ("meshdir", "texturedir", "assetdir"):
            compiler.attrib.pop(key, None)  # every file now has its in-memory name
    world.xml = ET.tostring(doc.root, encoding="unicode")
    return world

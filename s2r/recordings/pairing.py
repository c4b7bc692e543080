"""Stereo inputs from image folders and globs: find the images and pair left with right.

Three layouts are understood:

- a folder with two camera subfolders: ``left/`` and ``right/`` (``left/00.png`` pairs with ``right/00.png``),
  Kalibr/EuRoC's ``cam0/`` and ``cam1/`` (images directly inside or in ``camN/data/``; cam0 is taken as the
  left camera, and the calibration's swap check says so when it is not) or KITTI's ``image_0/`` and
  ``image_1/``; subfolder names are matched without regard to case;
- a folder of ``left*`` / ``right*`` files paired by the (last) number in their names
  (``left01.jpg`` with ``right01.jpg``; a missing partner is named, not guessed), or of files that carry
  ``left`` / ``right`` elsewhere in their names (``0001_left.png``);
- two globs (``--left 'cam0/*.png' --right 'cam1/*.png'``) or two folders (``--left cam0/ --right cam1/``) paired by
  that number, or by sorted order when the names carry no numbers.
"""

from __future__ import annotations

import glob as _glob
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from s2r.errors import CalibrationError
from s2r.fileio import protect_read_files
from s2r.recordings.frames import refuse_same_sides

__all__ = ["IMAGE_SUFFIXES", "PairSet", "find_mono_images", "find_stereo_pairs", "pair_by_number"]

#: File suffixes treated as images (case-insensitive).
IMAGE_SUFFIXES = frozenset({".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm", ".webp"})
_NUMBER = re.compile(r"(\d+)")


@dataclass(frozen=True)
class PairSet:
    """Paired image files: ``left[i]`` and ``right[i]`` show the same board; ``names[i]`` labels the pair.

    ``unpaired`` lists files whose partner is missing (they are skipped and reported).
    """

    left: tuple[Path, ...]
    right: tuple[Path, ...]
    names: tuple[str, ...]
    unpaired: tuple[Path, ...] = ()


def _images_in(folder: Path, prefix: str = "") -> list[Path]:
    if not folder.is_dir():  # a camera subfolder that is missing holds no images
        return []
    return sorted(p for p in folder.iterdir()
                  if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES and p.name.lower().startswith(prefix))


#: Camera subfolder pairs (left, right) understood, in order of preference.
CAMERA_SUBFOLDERS = (("left", "right"), ("cam0", "cam1"), ("image_0", "image_1"))


def _camera_subfolders(folder: Path) -> tuple[Path, Path] | None:
    """The (left, right) image folders of ``folder`` per :data:`CAMERA_SUBFOLDERS` (a ``data/`` folder inside
    one is used when it holds the images), or None."""
    children = {p.name.lower(): p for p in folder.iterdir() if p.is_dir()}
    for left_name, right_name in CAMERA_SUBFOLDERS:
        if left_name in children and right_name in children:
            return _data_folder(children[left_name]), _data_folder(children[right_name])
    return None


def _one_camera_subfolder(folder: Path) -> tuple[Path, Path] | None:
    """``(left, right)`` when ``folder`` holds one camera subfolder of a pair with images and not its partner
    (the missing one named as ``folder/<name>``, which pairs with nothing), else None."""
    children = {p.name.lower(): p for p in folder.iterdir() if p.is_dir()}
    for left_name, right_name in CAMERA_SUBFOLDERS:
        present = [children[n] for n in (left_name, right_name) if n in children]
        if len(present) == 1 and _images_in(_data_folder(present[0])):
            found = _data_folder(present[0])
            missing = folder / (right_name if left_name in children else left_name)
            return (found, missing) if left_name in children else (missing, found)
    return None


def _data_folder(folder: Path) -> Path:
    """``folder/data`` when the images are there (EuRoC / Kalibr bag extraction), else ``folder``."""
    return folder / "data" if (folder / "data").is_dir() and not _images_in(folder) else folder


def _images_named(folder: Path, word: str) -> list[Path]:
    """Images of ``folder`` whose names contain ``word`` (case-insensitive) and not the other side's word."""
    other = "right" if word == "left" else "left"
    return [p for p in _images_in(folder) if word in p.name.lower() and other not in p.name.lower()]


def _key(path: Path, *, prefix: str = "") -> str:
    """Pairing key: the last number in the name (as an int, so 01 == 1), else the stem without the prefix."""
    numbers = _NUMBER.findall(path.stem)
    if numbers:
        return str(int(numbers[-1]))
    return path.stem.lower().removeprefix(prefix)


def pair_by_number(left: Sequence[Path], right: Sequence[Path], *, left_prefix: str = "",
                   right_prefix: str = "") -> PairSet:
    """Pair files whose names carry the same number (or the same stem after the side prefix).

    CalibrationError naming the two files when two images of one side share a number, and naming the pairing
    problem (one side missing, or no number in common) when not one pair forms.
    """
    lk = _keyed(left, prefix=left_prefix)
    rk = _keyed(right, prefix=right_prefix)
    common = sorted(set(lk) & set(rk), key=lambda k: (len(k), k))
    if not common:
        raise _no_pairs_error(left, right)
    unpaired = sorted([lk[k] for k in set(lk) - set(rk)] + [rk[k] for k in set(rk) - set(lk)])
    return PairSet(left=tuple(lk[k] for k in common), right=tuple(rk[k] for k in common),
                   names=tuple(lk[k].stem for k in common), unpaired=tuple(unpaired))


def _keyed(files: Sequence[Path], *, prefix: str) -> dict[str, Path]:
    """``{pairing key: file}``; CalibrationError naming both files when two share a key."""
    keyed: dict[str, Path] = {}
    for path in files:
        key = _key(path, prefix=prefix)
        if key in keyed:
            raise CalibrationError(f"two images share one pairing number ({key}): {keyed[key].name} and {path.name}",
                                   path=str(path.parent),
                                   hint="give each left/right pair a unique number in its file names")
        keyed[key] = path
    return keyed


def _no_pairs_error(left: Sequence[Path], right: Sequence[Path]) -> CalibrationError:
    """The pairing problem when no left image has a right partner: one side missing, or no number in common."""
    if not left or not right:
        have, side, other = ("left", left, "right") if left else ("right", right, "left")
        return CalibrationError(
            f"{len(side)} {have} image{'s' if len(side) != 1 else ''} and no {other} images: stereo calibration "
            f"pairs each {have} image with a {other} one", path=str(Path(side[0]).parent),
            hint=f"add the {other} camera's images as {other}/ beside {have}/ or {other}NN.png beside {have}NN.png; "
                 "for one camera: s2r calibrate --mono")
    return CalibrationError(
        f"no left image shares a pairing number with a right image ({len(left)} left: {_span(left)}; "
        f"{len(right)} right: {_span(right)})", path=str(Path(left[0]).parent),
        hint="a pair is two files with one number in their names, e.g. left/07.png and right/07.png")


def _span(files: Sequence[Path]) -> str:
    """``first.png .. last.png`` of sorted ``files`` (one name when there is one)."""
    names = sorted(Path(p).name for p in files)
    return names[0] if len(names) == 1 else f"{names[0]} .. {names[-1]}"


def _expand(pattern: str, side: str) -> list[Path]:
    """The image files of a glob, or of a folder (every image directly inside it)."""
    if Path(pattern).is_dir():
        files = _images_in(Path(pattern))
    else:
        files = sorted(Path(p) for p in _glob.glob(pattern) if Path(p).suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise CalibrationError(f"--{side} glob matches no image files", path=pattern,
                               hint=f"check the pattern; image suffixes: {', '.join(sorted(IMAGE_SUFFIXES))}")
    return files


def find_stereo_pairs(folder: Path | None = None, *, left_glob: str | None = None,
                      right_glob: str | None = None) -> PairSet:
    """Find and pair the stereo images of ``folder`` (or of two globs); see the module docstring.

    Every image found (paired or not) is an input of the running command: no output may be one of them
    (:func:`s2r.fileio.protect_read_files`)."""
    pairs = _find_stereo_pairs(folder, left_glob=left_glob, right_glob=right_glob)
    protect_read_files([*pairs.left, *pairs.right, *pairs.unpaired])
    return pairs


def _find_stereo_pairs(folder: Path | None, *, left_glob: str | None, right_glob: str | None) -> PairSet:
    if left_glob is not None or right_glob is not None:
        if left_glob is None or right_glob is None:
            raise CalibrationError("--left and --right must be given together", field="--left/--right",
                                   hint="pass both globs, or an INPUT folder")
        left, right = _expand(left_glob, "left"), _expand(right_glob, "right")
        if not any(_NUMBER.search(p.stem) for p in left + right) and len(left) == len(right):
            return PairSet(left=tuple(left), right=tuple(right), names=tuple(p.stem for p in left))
        return pair_by_number(left, right)
    if folder is None:
        raise CalibrationError("no input given", hint="pass an INPUT folder, --left/--right globs or --bag")
    folder = Path(folder)
    if not folder.is_dir():
        raise CalibrationError("input folder not found" if not folder.exists() else "input is not a folder",
                               path=folder, hint="pass a folder with left/ and right/ or left*/right* images")
    subfolders = _camera_subfolders(folder) or _one_camera_subfolder(folder)
    if subfolders is not None:
        refuse_same_sides(  # left/ a link to right/: one camera's images twice
            subfolders[0], subfolders[1], field="FOLDER", error=CalibrationError)
        return pair_by_number(_images_in(subfolders[0]), _images_in(subfolders[1]))
    left, right = _images_in(folder, "left"), _images_in(folder, "right")
    if not left and not right:
        left, right = _images_named(folder, "left"), _images_named(folder, "right")
        if left or right:
            return pair_by_number(left, right)
        raise CalibrationError("no left/ and right/ subfolders and no left*/right* images", path=folder,
                               hint="put the images in left/ and right/, or name them leftNN.png / rightNN.png")
    return pair_by_number(left, right, left_prefix="left", right_prefix="right")


def find_mono_images(folder: Path | None = None, *, image_glob: str | None = None) -> list[Path]:
    """Images of one camera: a glob, a folder's ``left/`` subfolder, its ``left*`` files, or all its images (each an
    input of the running command: :func:`s2r.fileio.protect_read_files`)."""
    images = _find_mono_images(folder, image_glob=image_glob)
    protect_read_files(images)
    return images


def _find_mono_images(folder: Path | None, *, image_glob: str | None) -> list[Path]:
    if image_glob is not None:
        return _expand(image_glob, "left")
    if folder is None:
        raise CalibrationError("no input given", hint="pass an INPUT folder or --left GLOB")
    folder = Path(folder)
    if not folder.is_dir():
        raise CalibrationError("input folder not found", path=folder, hint="pass a folder of images")
    children = {p.name.lower(): p for p in folder.iterdir() if p.is_dir()}
    first = next((children[name] for name, _ in CAMERA_SUBFOLDERS if name in children), None)
    if first is not None:
        folder = _data_folder(first)
    images = _images_in(folder, "left") or _images_in(folder)
    if not images:
        raise CalibrationError("no image files in the folder", path=folder,
                               hint=f"image suffixes: {', '.join(sorted(IMAGE_SUFFIXES))}")
    return images

"""Calibration inputs from image folders and globs: moved to :mod:`s2r.recordings.pairing` (re-exported here for the
code that imports the old names)."""

from s2r.recordings.pairing import (
    CAMERA_SUBFOLDERS,
    IMAGE_SUFFIXES,
    PairSet,
    find_mono_images,
    find_stereo_pairs,
    pair_by_number,
)

__all__ = ["CAMERA_SUBFOLDERS", "IMAGE_SUFFIXES", "PairSet", "find_mono_images", "find_stereo_pairs", "pair_by_number"]

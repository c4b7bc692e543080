"""Preset and post-processing stage names, importable without OpenCV (the CLI builds its options from them)."""

from __future__ import annotations

__all__ = ["PRESETS", "STAGES"]

#: Every matcher preset, in the order the docs and benchmarks list them.
PRESETS: tuple[str, ...] = ("profile", "seed-sgbm", "fast", "bm", "ros-default")

#: Every post-processing stage name (see :mod:`s2r.depth.postprocess`).
STAGES: tuple[str, ...] = ("speckle", "lr-check", "median", "close", "fill", "seed-median", "seed-close")

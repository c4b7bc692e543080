"""How much work ``validate`` does: board views, scenes, distances and supersampling (default and --quick)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from s2r.validate.measures.depth_accuracy import DEFAULT_BINS_M

__all__ = ["FULL", "QUICK", "Settings"]


@dataclass(frozen=True)
class Settings:
    """How much work each stage does: board views and their supersampling, the distances (metres) of the
    planes (jittered per frame), whether they are "span" planes (default) or fronto-parallel ones, further
    ``(scene, distances)`` pairs ("slanted", "room"), and the scenes' supersampling (kept at 2: without
    anti-aliasing, 1x renders add matching error that is not the camera's), and the renderer that draws them
    (``--renderer``: "pybullet" or "mujoco", the latter optionally inside the user's MJCF ``scene_path``)."""

    @property
    def scenes(self) -> tuple[tuple[str, tuple[float, ...]], ...]:
        """Every ``(scene, distances_m)`` rendered for depth accuracy: one "span" plane per distance (tilted so its
        depth grows 1.5x across the image: every sub-pixel phase), or with ``span=False`` the old fronto-parallel
        planes (one sub-pixel phase each: their medians depend on the exact distances drawn); then the extras."""
        first = "span" if self.span else "planes"
        return ((first, self.distances_m), *self.extra_scenes)

    @property
    def all_distances_m(self) -> tuple[float, ...]:
        """Every distance of every scene, metres, sorted."""
        return tuple(sorted({d for _, ds in self.scenes for d in ds}))


    views: int
    supersample: int
    distances_m: tuple[float, ...]
    extra_scenes: tuple[tuple[str, tuple[float, ...]], ...] = ()
    span: bool = True
    scene_supersample: int = 2
    preset: str = "profile"
    seed: int = 0
    bins_m: tuple[tuple[float, float], ...] = DEFAULT_BINS_M
    renderer: str = "pybullet"
    scene_path: str | None = None
    scene_camera: str | None = None

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return {"views": self.views, "supersample": self.supersample, "scene_supersample": self.scene_supersample,
                "distances_m": list(self.distances_m), "span": self.span,
                "scenes": {name: list(ds) for name, ds in self.scenes}, "preset": self.preset, "seed": self.seed,
                "bins_m": [list(b) for b in self.bins_m], "renderer": self.renderer,
                **({"world": self.scene_path, "world_camera": self.scene_camera} if self.scene_path else {})}


#: Default settings (two profiles: about 2-3x the CPU time of QUICK; the README gives measured figures).
FULL = Settings(views=20, supersample=2, distances_m=(0.6, 0.85, 1.2, 1.6, 2.2, 2.7, 3.3, 4.0, 4.6))
#: ``--quick`` settings: fewer views (not supersampled) and planes.
QUICK = Settings(views=16, supersample=1, distances_m=(0.75, 1.5, 2.5, 4.0))



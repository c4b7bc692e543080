"""How much work ``validate`` does: board views, scenes, distances and supersampling (default and --quick)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from s2r.validate.depth_accuracy import DEFAULT_BINS_M

__all__ = ["FULL", "QUICK", "Settings"]


@dataclass(frozen=True)
class Settings:
    """How much work each stage does: board views and their supersampling, the distances (metres) of the
    fronto-parallel planes, further ``(scene, distances)`` pairs ("slanted", "room"), and the scenes'
    supersampling (kept at 2: without anti-aliasing, 1x renders add matching error that is not the camera's)."""

    @property
    def scenes(self) -> tuple[tuple[str, tuple[float, ...]], ...]:
        """Every ``(scene, distances_m)`` rendered for depth accuracy, the planes first."""
        return (("planes", self.distances_m), *self.extra_scenes)

    @property
    def all_distances_m(self) -> tuple[float, ...]:
        """Every distance of every scene, metres, sorted."""
        return tuple(sorted({d for _, ds in self.scenes for d in ds}))


    views: int
    supersample: int
    distances_m: tuple[float, ...]
    extra_scenes: tuple[tuple[str, tuple[float, ...]], ...] = ()
    scene_supersample: int = 2
    preset: str = "profile"
    seed: int = 0
    bins_m: tuple[tuple[float, float], ...] = DEFAULT_BINS_M

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return {"views": self.views, "supersample": self.supersample, "scene_supersample": self.scene_supersample,
                "distances_m": list(self.distances_m),
                "scenes": {name: list(ds) for name, ds in self.scenes}, "preset": self.preset, "seed": self.seed,
                "bins_m": [list(b) for b in self.bins_m]}


#: Default settings (two profiles: about 2-3x the CPU time of QUICK, README gives measured figures).
FULL = Settings(views=20, supersample=2, distances_m=(0.6, 0.9, 1.25, 1.75, 2.25, 2.75, 3.5, 4.5),
                extra_scenes=(("slanted", (1.5,)),))
#: ``--quick`` settings (two profiles: 34 s of CPU time measured on 2 cores): fewer views (not supersampled) and
#: planes, no slanted plane.
QUICK = Settings(views=16, supersample=1, distances_m=(0.75, 1.5, 2.5, 4.0))



"""The expensive per-profile stages as independent tasks, run in parallel processes with one progress bar.

Each task (recovered calibration or depth accuracy of one profile) runs its renders and solves in one
process; tasks of both profiles run side by side (``jobs`` processes). Progress from inside the workers comes
back through a manager queue and is folded into one overall percentage.
"""

from __future__ import annotations

import logging
import queue as queue_mod
from concurrent.futures import FIRST_COMPLETED, Future, wait
from multiprocessing import Manager
from typing import Any

from s2r.executor import local_pool
from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback, report
from s2r.validate.measures.depth_accuracy import measure_depth_accuracy
from s2r.validate.measures.recovery import recover_calibration
from s2r.validate.settings import Settings
from s2r.validate.tolerances import Tolerances

__all__ = ["run_tasks"]

TaskKey = tuple[str, str]  # (kind, role)
#: Share of a task's time spent rendering (labels starting "render"); the rest is calibration or matching.
_RENDER_SHARE = 0.8


class _Forward:
    """Picklable progress callback that forwards ``(key, done, total, label)`` to a queue."""

    def __init__(self, channel: Any, key: TaskKey) -> None:
        self.channel = channel
        self.key = key

    def __call__(self, done: int, total: int, label: str) -> None:
        self.channel.put((self.key, done, total, label))


class _Overall:
    """Folds per-task progress into one percentage reported as ``validate``."""

    def __init__(self, keys: list[TaskKey], progress: ProgressCallback | None) -> None:
        self.fractions = dict.fromkeys(keys, 0.0)
        self.progress = progress
        self.done = False

    def update(self, key: TaskKey, done: int, total: int, label: str) -> None:
        part = done / total if total > 0 else 0.0
        value = _RENDER_SHARE * part if label.startswith("render") else _RENDER_SHARE + (1 - _RENDER_SHARE) * part
        self.fractions[key] = max(self.fractions[key], min(value, 1.0))
        self._report()

    def finish(self, key: TaskKey) -> None:
        self.fractions[key] = 1.0
        self._report()

    def _report(self) -> None:
        if self.done:
            return
        self.done = all(f >= 1.0 for f in self.fractions.values())
        share = sum(self.fractions.values()) / len(self.fractions)
        report(self.progress, 100 if self.done else min(round(100 * share), 99), 100, "validate %")


class _Local:
    """In-process progress callback for one task."""

    def __init__(self, overall: _Overall, key: TaskKey) -> None:
        self.overall = overall
        self.key = key

    def __call__(self, done: int, total: int, label: str) -> None:
        self.overall.update(self.key, done, total, label)


def _task(kind: str, profile: StereoProfile, settings: Settings, tol: Tolerances,
          progress: ProgressCallback | None = None) -> Any:
    if kind == "recovery":
        return recover_calibration(profile, tol, views=settings.views, supersample=settings.supersample,
                                   seed=settings.seed, jobs=1, progress=progress, renderer=settings.renderer,
                                   scene_path=settings.scene_path, scene_camera=settings.scene_camera)
    # validate() already warned about this preset's range (check_distances): do not print it a second time
    presets_log = logging.getLogger("s2r.depth.presets")
    level = presets_log.level
    presets_log.setLevel(logging.ERROR)
    try:
        return measure_depth_accuracy(profile, preset=settings.preset, scenes=settings.scenes,
                                      bins=settings.bins_m, supersample=settings.scene_supersample,
                                      seed=settings.seed, jobs=1, progress=progress, renderer=settings.renderer,
                                      scene_path=settings.scene_path, scene_camera=settings.scene_camera)
    finally:
        presets_log.setLevel(level)


def _drain(channel: Any, overall: _Overall) -> None:
    while True:
        try:
            key, done, total, label = channel.get_nowait()
        except queue_mod.Empty:
            return
        overall.update(key, done, total, label)


def _longest_first(roles: dict[str, StereoProfile]) -> list[TaskKey]:
    """The tasks longest first, so the pool's first-come queue packs them onto its workers as well as it can
    (longest-processing-time-first list scheduling): the depth tasks (most of the rendering), then the recovery
    tasks, each kind by the profile's pixel count (rendering and matching cost per pixel). With two workers the
    larger profile's recovery then follows the smaller one's depth task: --quick's critical path on two idle cores,
    from per-task CPU times measured at jobs=1, 5.75 -> 5.63 s, the default's 15.4 -> 14.6 s (848x480 real profile
    beside a 640x480 sim one)."""
    pixels = {role: p.left.width_px * p.left.height_px for role, p in roles.items()}
    by_size = sorted(roles, key=lambda role: -pixels[role])  # stable: equal sizes keep the roles' order
    return [(kind, role) for kind in ("depth", "recovery") for role in by_size]


def run_tasks(roles: dict[str, StereoProfile], settings: Settings, tol: Tolerances, *, jobs: int,
              progress: ProgressCallback | None) -> dict[TaskKey, Any]:
    """Recovery and depth-accuracy results keyed ``(kind, role)``; ``jobs`` <= 1 runs them in this process."""
    keys = _longest_first(roles)
    overall = _Overall(keys, progress)
    results: dict[TaskKey, Any] = {}
    report(progress, 0, 100, "validate %")
    if jobs <= 1:
        for key in keys:
            results[key] = _task(key[0], roles[key[1]], settings, tol, _Local(overall, key))
            overall.finish(key)
        return results
    with Manager() as manager, local_pool(min(jobs, len(keys))) as pool:
        channel = manager.Queue()
        futures: dict[Future[Any], TaskKey] = {
            pool.submit(_task, kind, roles[role], settings, tol, _Forward(channel, (kind, role))): (kind, role)
            for kind, role in keys}
        pending = set(futures)
        while pending:
            done, pending = wait(pending, timeout=0.1, return_when=FIRST_COMPLETED)
            _drain(channel, overall)
            for fut in done:
                results[futures[fut]] = fut.result()
                overall.finish(futures[fut])
    return results

"""``validate``: the whole comparison of a sim profile with a real one (or one profile's self-check).

Stages: parameter table, projection difference, theoretical depth resolution (instant), then for each profile
the recovered calibration (render boards + calibrate) and the depth accuracy (render scenes + depth
pipeline). The expensive per-profile stages run as independent tasks in parallel processes (``jobs``).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from s2r.errors import ValidateError
from s2r.executor import usable_cores
from s2r.profile import StereoProfile
from s2r.validate.advice.causes import RootCause, group_failures
from s2r.validate.advice.edits import Edit, suggest_edits
from s2r.validate.advice.mujoco import is_mujoco_sim, suggest_mujoco_edits
from s2r.validate.measures.depth_accuracy import DepthAccuracy
from s2r.validate.measures.params import ParamRow, parameter_table
from s2r.validate.measures.projection import ProjectionDiff, projection_difference
from s2r.validate.measures.recovery import RecoveryResult
from s2r.validate.measures.resolution import DepthResolution, depth_resolution
from s2r.validate.settings import FULL, QUICK, Settings
from s2r.validate.tasks import run_tasks
from s2r.validate.tolerances import Tolerances
from s2r.validate.verdict import (
    Check,
    depth_checks,
    depth_gap_checks,
    parameter_checks,
    projection_checks,
    recovery_checks,
)

__all__ = ["FULL", "QUICK", "RecordingSpec", "Settings", "ValidationResult", "check_distances", "distances_in_view",
           "validate"]

log = logging.getLogger(__name__)

#: Distances (metres) of the theoretical depth-resolution table.
RESOLUTION_DISTANCES_M = (0.5, 1.0, 2.0, 3.0, 5.0)


@dataclass
class ValidationResult:
    """Every figure of one validation run; ``roles`` maps ``sim``/``real`` (or ``profile``) to profiles."""

    roles: dict[str, StereoProfile]
    settings: Settings
    tolerances: Tolerances
    params: list[ParamRow] = field(default_factory=list)
    projection: list[ProjectionDiff] = field(default_factory=list)
    resolution: dict[str, DepthResolution] = field(default_factory=dict)
    recovery: dict[str, RecoveryResult] = field(default_factory=dict)
    depth: dict[str, DepthAccuracy] = field(default_factory=dict)
    edits: list[Edit] = field(default_factory=list)
    gazebo_xml: str | None = None
    notes: list[str] = field(default_factory=list)
    checks: list[Check] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)
    recording: Any = None  # s2r.validate.recording.compare.RecordingComparison with --recording

    @property
    def pair(self) -> bool:
        """True for a sim-vs-real comparison, False for one profile's self-check."""
        return "real" in self.roles

    @property
    def passed(self) -> bool:
        """True when every check passes."""
        return all(c.passed for c in self.checks)

    @property
    def failures(self) -> list[Check]:
        """The failing checks, in report order."""
        return [c for c in self.checks if not c.passed]

    @property
    def root_causes(self) -> list[RootCause]:
        """The failures grouped by the sim parameter that explains them (see :mod:`s2r.validate.advice.causes`)."""
        sim, real = self.roles.get("sim"), self.roles.get("real")
        if sim is not None and real is not None:  # compared in the pixels the images obey, as the parameters are
            sim, real = sim.in_opencv_pixels(), real.in_opencv_pixels()
        return group_failures(self.checks, self.params, self.edits, sim=sim, real=real, preset=self.settings.preset)

    def as_dict(self) -> dict[str, Any]:
        """Every figure as plain JSON-ready data."""
        return {
            "mode": "sim-vs-real" if self.pair else "self-check",
            "profiles": {role: p.name for role, p in self.roles.items()},
            "passed": self.passed, "root_causes": [c.as_dict() for c in self.root_causes],
            "settings": self.settings.as_dict(), "tolerances": self.tolerances.as_dict(),
            "parameters": [r.as_dict() for r in self.params],
            "projection": [d.as_dict() for d in self.projection],
            "resolution": {k: v.as_dict() for k, v in self.resolution.items()},
            "recovery": {k: v.as_dict() for k, v in self.recovery.items()},
            "depth": {k: v.as_dict() for k, v in self.depth.items()},
            "edits": [e.as_dict() for e in self.edits], "gazebo_xml": self.gazebo_xml, "notes": self.notes,
            "checks": [c.as_dict() for c in self.checks], "failures": [c.text for c in self.failures],
            "seconds": self.seconds,
            **({"recording": self.recording.as_dict()} if self.recording is not None else {}),
        }


@dataclass(frozen=True)
class RecordingSpec:
    """Recordings to compare on: the real one (``folder``: any ``SRC`` of :mod:`s2r.quality.source`, or a
    ``RecordingSource`` built from the shared recording options), the sim's own (``sim``, None: rendered at the
    recovered poses), the board's inner corners and square (metres)."""

    folder: Any
    pattern: tuple[int, int] = (9, 6)
    square_m: float = 0.025
    sim: str | None = None


def visible_range_m(profile: StereoProfile, preset: str) -> tuple[float, float, int]:
    """Nearest and farthest depth (metres) the preset's disparity range sees through ``profile``, and that range
    (pixels)."""
    from s2r.depth.pipeline import StereoPipeline

    pipe = StereoPipeline(profile, preset=preset)
    fb = pipe.rectification.fx_px * pipe.rectification.baseline_m
    d_max = pipe.config.min_disparity + pipe.config.num_disparities - 1
    return fb / max(d_max, 1), fb / max(pipe.config.min_disparity, 1), pipe.config.num_disparities


def distances_in_view(profiles: Sequence[StereoProfile], preset: str, distances_m: Sequence[float]
                      ) -> tuple[float, ...]:
    """The default ``distances_m`` every profile's matcher sees, with a warning naming the ones dropped (a 4 mm
    or 64x48 rig sees under 2 m); all of them when fewer than two are seen (:func:`check_distances` then
    refuses)."""
    ranges = {p.name: visible_range_m(p, preset)[:2] for p in profiles}
    kept = tuple(d for d in distances_m if all(lo <= d <= hi for lo, hi in ranges.values()))
    if len(kept) < 2:  # one plane is no accuracy curve: keep them all and let check_distances refuse
        return tuple(distances_m)
    if len(kept) < len(distances_m):
        seen = "; ".join(f"{name} sees {lo:.2f}-{hi:.1f} m" for name, (lo, hi) in ranges.items())
        log.warning("validating at %s m only, not %s m (%s; pass --distances to choose)",
                    ", ".join(f"{d:g}" for d in kept),
                    ", ".join(f"{d:g}" for d in distances_m if d not in kept), seen)
    return kept


def check_distances(profile: StereoProfile, preset: str, distances_m: Sequence[float]) -> None:
    """Raise :class:`ValidateError` when the preset's disparity range cannot see every requested distance."""
    nearest, farthest, disparities = visible_range_m(profile, preset)
    unseen = [d for d in distances_m if d < nearest or d > farthest]
    if unseen:
        raise ValidateError(
            f"the {preset!r} matcher of profile {profile.name} ({disparities} disparities) sees "
            f"{nearest:.2f}-{farthest:.1f} m, not {', '.join(f'{d:g}' for d in unseen)} m",
            field="matcher", hint="lower matcher.min_depth_m / num_disparities in the profile, choose another "
            "--preset, or pass --distances inside that range")


def convention_notes(sim: StereoProfile, real: StereoProfile) -> list[str]:
    """One note per profile whose declared principal point is offset from its images' centre (pixels)."""
    notes = []
    for role, profile in (("sim", sim), ("real", real)):
        offset = profile.published_offset_px
        if offset:
            notes.append(
                f"{role} profile {profile.name} follows the {profile.provenance.convention} convention: it "
                f"declares its principal point {offset:g} px right of and below the centre its images obey; "
                f"parameters and projections below compare the images' geometry (OpenCV 0-based pixels), and "
                f"code that rectifies those images with the declared camera_info is {offset:g} px off")
    return notes


def _gazebo_xml(real: StereoProfile) -> str | None:
    try:
        from s2r.sources.export.gazebo import export_gazebo
    except ImportError:  # pragma: no cover - the exporter ships with s2r.sources
        return None
    xml, warnings = export_gazebo(real, fmt="urdf")
    for warning in warnings:
        log.debug("export-gazebo: %s", warning)
    return str(xml)


def _static_stages(result: ValidationResult, sim: StereoProfile, real: StereoProfile | None) -> None:
    tol = result.tolerances
    for role, profile in result.roles.items():
        result.resolution[role] = depth_resolution(profile, RESOLUTION_DISTANCES_M)
    if real is None:
        return
    result.notes += convention_notes(sim, real)
    # Compare the geometry the images obey: a sim profile declares what its simulator publishes, which
    # (gazebo-classic, gz-sim) sits a fixed offset from the centre its images really have.
    sim, real = sim.in_opencv_pixels(), real.in_opencv_pixels()
    result.params = parameter_table(sim, real, tol)
    result.projection = projection_difference(sim, real, distance_m=tol.working_distance_m)
    if is_mujoco_sim(sim):  # an MJCF's <camera> attributes, not a Gazebo sensor's
        result.edits = suggest_mujoco_edits(sim, real, result.params, principal_point_px=tol.principal_point_px)
        return
    result.edits = suggest_edits(sim, real, result.params, principal_point_px=tol.principal_point_px)
    if result.edits:
        result.gazebo_xml = _gazebo_xml(real)
        if result.settings.renderer == "mujoco":
            result.edits.append(_mujoco_edit(sim, real))


def _mujoco_edit(sim: StereoProfile, real: StereoProfile) -> Edit:
    """The MJCF camera pair that renders like the real camera, with the lens residual MJCF cannot express."""
    from s2r.sources.export.mujoco import distortion_residual_px

    worst = max(distortion_residual_px(real.left)[0], distortion_residual_px(real.right)[0])
    lens = f" (MJCF has no lens model: {worst:.2f} px left by the distortion)" if worst >= 0.01 else ""
    return Edit("MJCF cameras", sim.name, real.name,
                f"s2r profile export-mujoco {real.name} -o {real.name}_cameras.xml{lens}")


def _collect_checks(result: ValidationResult) -> list[Check]:
    tol = result.tolerances
    checks = parameter_checks(result.params) + projection_checks(result.projection, tol)
    for role, rec in result.recovery.items():
        checks += recovery_checks(rec, role)
    for role, acc in result.depth.items():
        checks += depth_checks(acc, tol, role)
    if result.pair:
        checks += depth_gap_checks(result.depth["sim"], result.depth["real"], tol)
    if result.recording is not None:
        from s2r.validate.recording.compare import recording_checks

        checks += recording_checks(result.recording)
    return checks


def _compare_recording(sim: StereoProfile, real: StereoProfile, spec: RecordingSpec, settings: Settings,
                       tol: Tolerances) -> Any:
    from s2r.validate.recording.compare import compare_recording, compare_recordings

    if spec.sim is not None:
        return compare_recordings(sim, real, sim_source=spec.sim, real_source=spec.folder, pattern=spec.pattern,
                                  square_m=spec.square_m, preset=settings.preset, tol=tol, seed=settings.seed)
    return compare_recording(sim, real, spec.folder, pattern=spec.pattern, square_m=spec.square_m,
                             preset=settings.preset, tol=tol, seed=settings.seed,
                             renderer=(settings.renderer, settings.scene_path, settings.scene_camera))


def validate(sim: StereoProfile, real: StereoProfile | None = None, *, tolerances: Tolerances | None = None,
             settings: Settings = FULL, jobs: int | None = None,
             progress: Callable[[int, int, str], None] | None = None,
             recording: RecordingSpec | None = None) -> ValidationResult:
    """Validate ``sim`` against ``real`` (or ``sim`` alone: its self-check). See the module docstring.

    With ``recording`` (needs ``real``), the real camera is also measured on its own recording and the sim on its
    own (``recording.sim``) or on renders of the same boards at the recovered poses
    (:mod:`s2r.validate.recording.compare`).

    Raises:
        ValidateError: a profile's matcher cannot see the requested distances.
    """
    tol = Tolerances() if tolerances is None else tolerances
    roles = {"sim": sim, "real": real} if real is not None else {"profile": sim}
    for profile in roles.values():
        check_distances(profile, settings.preset, settings.all_distances_m)
    result = ValidationResult(roles=roles, settings=settings, tolerances=tol)
    start = time.perf_counter()
    _static_stages(result, sim, real)
    result.seconds["static"] = time.perf_counter() - start
    workers = jobs if jobs is not None else usable_cores()
    outputs = run_tasks(roles, settings, tol, jobs=workers, progress=progress)
    for (kind, role), value in sorted(outputs.items(), key=lambda item: list(roles).index(item[0][1])):
        if kind == "recovery":
            result.recovery[role] = value
        else:
            result.depth[role] = value
        for stage, secs in value.seconds.items():
            result.seconds[f"{stage} ({role})"] = secs
    if recording is not None and real is not None:
        began = time.perf_counter()
        result.recording = _compare_recording(sim, real, recording, settings, tol)
        result.seconds["recording"] = time.perf_counter() - began
    result.checks = _collect_checks(result)
    result.seconds["total"] = time.perf_counter() - start
    return result

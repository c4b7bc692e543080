"""Recovered calibration: render checkerboards through a profile, calibrate them, compare with the profile.

This checks the whole chain on each profile: PyBullet renders the boards exactly through the declared
camera model (:func:`s2r.render.boards.sets.render_board_set`), s2r's own calibration
(:func:`s2r.calib.calibrate_stereo`) solves them, and each recovered parameter is compared with the
declared one, in units of the calibration's predicted one-sigma standard deviation.
"""

from __future__ import annotations

import logging
import math
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from s2r.geometry import rotation_angle_rad
from s2r.profile import Camera, StereoProfile
from s2r.progress import ProgressCallback
from s2r.validate.tolerances import Tolerances

__all__ = ["RecoveryResult", "RecoveryRow", "compare_recovered", "recover_calibration"]


@dataclass(frozen=True)
class RecoveryRow:
    """One recovered parameter: ``error = recovered - declared`` (parameter units), ``std`` the predicted
    one-sigma uncertainty (None when the calibration gives none), ``n_sigma = |error| / std``, ``floor``
    the absolute error always accepted; ``passed`` when within ``recovery_sigma`` sigmas or the floor."""

    name: str
    unit: str
    declared: float
    recovered: float
    error: float
    std: float | None
    n_sigma: float | None
    floor: float
    passed: bool

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return asdict(self)


@dataclass(frozen=True)
class RecoveryResult:
    """Recovered-calibration figures of one profile: rows, calibration RMS (px), views used, timings (s)."""

    profile: str
    rows: list[RecoveryRow]
    rms_px: float | None
    views_used: int
    views_rendered: int
    seconds: dict[str, float] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()

    @property
    def passed(self) -> bool:
        """True when every recovered parameter is within its tolerance."""
        return all(r.passed for r in self.rows)

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return {"profile": self.profile, "passed": self.passed, "rms_px": self.rms_px,
                "views_used": self.views_used, "views_rendered": self.views_rendered,
                "seconds": self.seconds, "warnings": list(self.warnings), "rows": [r.as_dict() for r in self.rows]}


def _row(name: str, unit: str, declared: float, recovered: float, std: float | None, floor: float,
         k_sigma: float) -> RecoveryRow:
    error = recovered - declared
    n_sigma = abs(error) / std if std else None
    ok = abs(error) <= floor or (n_sigma is not None and n_sigma <= k_sigma)
    return RecoveryRow(name, unit, declared, recovered, error, std, n_sigma, floor, ok)


def _camera_rows(side: str, declared: Camera, recovered: Camera, tol: Tolerances) -> list[RecoveryRow]:
    std = recovered.std
    rows = []
    for key in ("fx_px", "fy_px", "cx_px", "cy_px"):
        floor = tol.recovery_focal_rel * getattr(declared, key) if key[0] == "f" else tol.recovery_pp_px
        rows.append(_row(f"{side} {key[:2]}", "px", float(getattr(declared, key)), float(getattr(recovered, key)),
                         None if std is None else getattr(std, key), floor, tol.recovery_sigma))
    return rows


def compare_recovered(declared: StereoProfile, recovered: StereoProfile, tol: Tolerances) -> list[RecoveryRow]:
    """Recovered against declared: fx, fy, cx, cy of both cameras, baseline and inter-camera rotation."""
    rows = _camera_rows("left", declared.left, recovered.left, tol)
    rows += _camera_rows("right", declared.right, recovered.right, tol)
    rows.append(_row("baseline", "m", declared.baseline_m, recovered.baseline_m,
                     recovered.extrinsics.baseline_std_m, tol.recovery_baseline_rel * declared.baseline_m,
                     tol.recovery_sigma))
    angle = math.degrees(rotation_angle_rad(recovered.R @ declared.R.T))
    rows.append(_row("rotation error", "deg", 0.0, angle, None, tol.recovery_rotation_deg, tol.recovery_sigma))
    return rows


def lens_model_for(profile: StereoProfile) -> str:
    """The calibration lens model (a ``--distortion`` choice) with exactly the terms ``profile``'s lenses use.

    The test bench asks whether renderer + calibrator give back what was rendered; freeing terms the rendered
    lens does not have (tangential terms of a sim lens, on 16 views at 1x) only adds their noise to cx/cy.
    """
    if any(cam.distortion.model == "rational_polynomial" for cam in (profile.left, profile.right)):
        return "rational"
    both = [profile.left.distortion.coefficients, profile.right.distortion.coefficients]
    if any(len(c) > 4 and c[4] != 0.0 for c in both):
        return "plumb_bob"
    if any(len(c) > 3 and (c[2] != 0.0 or c[3] != 0.0) for c in both):
        return "k1k2p1p2"
    return "k1k2"


def recover_calibration(profile: StereoProfile, tol: Tolerances, *, views: int = 20, supersample: int = 2,
                        seed: int = 0, jobs: int | None = 1, work_dir: Path | None = None,
                        progress: ProgressCallback | None = None, renderer: str = "pybullet",
                        scene_path: str | None = None, scene_camera: str | None = None) -> RecoveryResult:
    """Render ``views`` board pairs through ``profile``, calibrate them, compare (see module doc).

    Images go to a temporary folder (or ``work_dir``), removed afterwards when temporary. ``renderer`` ("pybullet"
    or "mujoco") draws them, MuJoCo optionally inside the MJCF world ``scene_path`` (left camera at ``scene_camera``).
    """
    from s2r.calib import calibrate_stereo
    from s2r.render.backend import RendererChoice
    from s2r.render.boards.sets import render_board_set

    with tempfile.TemporaryDirectory(prefix="s2r-validate-boards-") as tmp:
        out_dir = Path(tmp) if work_dir is None else work_dir
        start = time.perf_counter()
        boards = render_board_set(profile, out_dir / "boards", views=views, seed=seed, supersample=supersample,
                                  jobs=jobs, force=True, progress=progress, temporary=work_dir is None,
                                  renderer=RendererChoice(renderer, scene_path, scene_camera))
        rendered = time.perf_counter()
        calib_log = logging.getLogger("s2r.calib")
        level = calib_log.level
        calib_log.setLevel(logging.ERROR)  # coverage advice is kept in the result, not shown as warnings
        try:
            if profile.left.distortion.model == "equidistant":  # a fisheye lens: OpenCV's equidistant model
                from s2r.calib.solve.pipelines.target_stereo import calibrate_stereo_target
                from s2r.targets import CheckerboardTarget

                board = CheckerboardTarget(target_type="checkerboard", targetCols=9, targetRows=6,
                                           rowSpacingMeters=0.025, colSpacingMeters=0.025)
                calib = calibrate_stereo_target(boards.left_paths, boards.right_paths, target=board, lens="fisheye",
                                                name=f"{profile.name}_recovered", jobs=jobs, progress=progress)
            else:
                calib = calibrate_stereo(boards.left_paths, boards.right_paths, name=f"{profile.name}_recovered",
                                         distortion=lens_model_for(profile), jobs=jobs, progress=progress)
        finally:
            calib_log.setLevel(level)
        done = time.perf_counter()
    recovered = calib.profile
    quality = recovered.provenance.calibration
    return RecoveryResult(
        profile=profile.name, rows=compare_recovered(profile, recovered, tol),
        rms_px=None if quality is None else quality.rms_stereo_px,
        views_used=len(boards.left_paths) if quality is None else quality.views_used,
        views_rendered=len(boards.left_paths),
        seconds={"render_boards": rendered - start, "calibrate": done - rendered},
        warnings=tuple(calib.warnings),
    )

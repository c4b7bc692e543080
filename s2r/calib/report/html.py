"""``s2r calibrate --report``: a self-contained HTML page of a calibration (figures embedded).

Stereo sections: the verdict (good / check / poor with its reasons), summary and warnings, the parameter
table with standard deviations and the signed translation, the lens model comparison (held-out error),
per-view errors (bar chart, a thumbnail of every view with its error, a table of every view), per-corner
residual vectors and the board poses in 3D, coverage footprints with pixel axes, one detection overlay
and a rectified pair with horizontal lines to judge the epipolar alignment.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect.chessboard import board_object_points
from s2r.calib.report.plots import (
    board_poses_3d,
    coverage_maps,
    projection_uncertainty,
    residual_vectors,
    thumbnail_strip,
)
from s2r.calib.solve.honesty.projection import ProjectionMap
from s2r.calib.solve.pipelines.mono import MonoCalibration
from s2r.calib.solve.pipelines.stereo import StereoCalibration
from s2r.fileio import OutputBatch
from s2r.htmlreport import (
    ReportSection,
    figure_to_data_uri,
    html_fragment,
    html_table,
    image_to_data_uri,
    write_report,
)
from s2r.profile import Camera
from s2r.rectification import stereo_rectification

__all__ = ["calibration_sections", "write_calibration_report"]

Image = NDArray[np.uint8]
#: OpenCV's names of each model's distortion coefficients, in order.
_DISTORTION_NAMES = {
    "plumb_bob": ("k1", "k2", "p1", "p2", "k3"),
    "rational_polynomial": ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"),
    "equidistant": ("k1", "k2", "k3", "k4"),
}


def _camera_rows(label: str, cam: Camera) -> list[list[Any]]:
    std = cam.std
    rows: list[list[Any]] = []
    for key, value in (("fx_px", cam.fx_px), ("fy_px", cam.fy_px), ("cx_px", cam.cx_px), ("cy_px", cam.cy_px)):
        sd = None if std is None else getattr(std, key)
        rows.append([f"{label} {key}", value, sd, None if sd is None else f"{100 * sd / value:.3f} %"])
    dstd = (std.distortion if std is not None else None) or ()
    names = _DISTORTION_NAMES[cam.distortion.model]
    for i, coef in enumerate(cam.distortion.coefficients):
        sd = dstd[i] if i < len(dstd) else None
        rows.append([f"{label} {names[i]}", coef, sd, "fixed at 0" if coef == 0.0 and not sd else ""])
    return rows


def _error_chart(names: list[str], series: dict[str, list[float]], used: list[bool], threshold: float) -> str:
    fig, ax = plt.subplots(figsize=(max(6.0, 0.35 * len(names) + 2), 3.4))
    x = np.arange(len(names))
    width = 0.8 / max(1, len(series))
    for k, (label, values) in enumerate(series.items()):
        bars = ax.bar(x + (k - (len(series) - 1) / 2) * width, values, width, label=label)
        for bar, ok in zip(bars, used, strict=True):
            if not ok:
                bar.set_hatch("//")
                bar.set_edgecolor("red")
    ax.axhline(threshold, color="red", linestyle="--", linewidth=1, label=f"threshold {threshold:.2f} px")
    ax.set_xticks(x, [n if ok else f"{n} (dropped)" for n, ok in zip(names, used, strict=True)],
                  rotation=70, fontsize=7)
    ax.set_ylabel("RMS reprojection error (px)")
    ax.legend(fontsize=8)
    return figure_to_data_uri(fig)


def _overlay(image: Image, corners: NDArray[np.float32], pattern: tuple[int, int]) -> str:
    colour = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image.copy()
    if len(corners) == pattern[0] * pattern[1]:
        cv2.drawChessboardCorners(colour, pattern, corners.reshape(-1, 1, 2), True)
    else:  # a partial view of a target: the corners seen
        for x, y in corners.reshape(-1, 2):
            cv2.circle(colour, (round(float(x)), round(float(y))), 4, (0, 0, 255), 1, cv2.LINE_AA)
    return image_to_data_uri(colour)


def _rectified_pair(result: StereoCalibration, left: Image, right: Image) -> str:
    p = result.profile
    rect = stereo_rectification(p)
    out = []
    for img, cam, R, P in ((left, p.left, rect.R1, rect.P1), (right, p.right, rect.R2, rect.P2)):
        if cam.distortion.model == "equidistant":
            m1, m2 = cv2.fisheye.initUndistortRectifyMap(cam.K, cam.D, R, P[:, :3], p.image_size, cv2.CV_32FC1)
        else:
            m1, m2 = cv2.initUndistortRectifyMap(cam.K, cam.D, R, P, p.image_size, cv2.CV_32FC1)
        warped = cv2.remap(img, m1, m2, cv2.INTER_LINEAR)
        out.append(cv2.cvtColor(warped, cv2.COLOR_GRAY2BGR) if warped.ndim == 2 else warped)
    pair = np.hstack(out)
    for y in range(0, pair.shape[0], max(16, pair.shape[0] // 16)):
        cv2.line(pair, (0, y), (pair.shape[1] - 1, y), (0, 255, 0), 1)
    return image_to_data_uri(pair)


def _sample(result: StereoCalibration | MonoCalibration) -> tuple[Image, Image | None] | None:
    if isinstance(result, MonoCalibration):
        img = None if result.sample_path is None else cv2.imread(str(result.sample_path))
        return None if img is None else (np.asarray(img, np.uint8), None)
    if result.sample_images is not None:
        return result.sample_images
    if result.sample_paths is None:
        return None
    left, right = (cv2.imread(str(p)) for p in result.sample_paths)
    if left is None or right is None:
        return None
    return np.asarray(left, np.uint8), np.asarray(right, np.uint8)


def _dropped_table(result: StereoCalibration | MonoCalibration) -> str:
    return html_table(["image or view", "RMS (px)", "reason"],
                      [[d.name, d.rms_px, d.reason] for d in result.dropped])


_BANNER = {"good": "pass", "check": "warn", "poor": "fail"}


def _verdict_section(result: StereoCalibration | MonoCalibration) -> ReportSection:
    v = result.verdict
    if v is None:
        return ReportSection("Verdict", paragraphs=["no verdict (computed by calibrate_stereo / calibrate_mono)"])
    items = html_fragment("<ul>{% for r in reasons %}<li><b>{{ r.level }}</b>: {{ r.text }}</li>{% endfor %}</ul>",
                          reasons=v.reasons)
    return ReportSection("Verdict", banner=(_BANNER[v.level], f"{v.level.upper()}"), paragraphs=[items])


def _extrinsic_rows(result: StereoCalibration) -> list[list[Any]]:
    p = result.profile
    sol = result.solution
    centre = -p.R.T @ p.T
    rows: list[list[Any]] = [[f"T{axis} (mm, signed)", f"{1000 * v:+.3f}", None, ""]
                             for axis, v in zip("xyz", p.T, strict=True)]
    side = "right of" if centre[0] > 0 else "LEFT of"
    rows.append(["right camera centre (mm, left frame)", ", ".join(f"{1000 * v:+.2f}" for v in centre), None,
                 f"{side} the left camera"])
    b_std = p.extrinsics.baseline_std_m
    rows.append(["baseline_m", p.baseline_m, b_std, "" if not b_std else f"{100 * b_std / p.baseline_m:.3g} %"])
    r_std = None if sol is None or not np.isfinite(sol.rotation_std_deg) else sol.rotation_std_deg
    rows.append(["rotation_deg", float(np.degrees(p.rotation_angle_rad)), r_std, ""])
    return rows


def _models_table(result: StereoCalibration | MonoCalibration) -> str:
    if result.models is None:
        return html_fragment("<p class='note'>model comparison not computed</p>")
    rows = [[s.model + (" (used)" if s.chosen else ""), s.heldout_px, " ".join(f"{f:.3f}" for f in s.folds_px),
             "best" if s.model == result.models.best else ""] for s in result.models.scores]
    what = ("stereo held-out error: pairs left out of the fit, one board pose per pair fitted to both cameras"
            if isinstance(result, StereoCalibration) else "held-out reprojection error: views left out of the fit")
    return html_table(["lens model (--distortion)", "held-out RMS (px)", "per fold (px)", ""], rows,
                      caption=f"{what}, each model", left=[0, 2])


def _views_table(result: StereoCalibration) -> str:
    rows = [[v.name, v.left_px, v.right_px, v.stereo_px, "used" if v.used else v.reason] for v in result.views]
    rows += [[d.name, None, None, d.rms_px, d.reason] for d in result.dropped
             if not d.reason.startswith("outlier")]
    rows += [[f"{g['name']} (corners)", None, None, None, f"{g['left']} left / {g['right']} right corners left out: "
              f"{g['reason']}"] for g in result.corner_groups()]
    return html_table(["view", "left RMS (px)", "right RMS (px)", "both (px)", "status"], rows,
                      caption="every view: used, dropped as outlier, or skipped", left=[0, 4])


def _board(pattern: tuple[int, int], square_m: float) -> str:
    return f"chessboard {pattern[0]}x{pattern[1]} inner corners, {square_m * 1000:g} mm squares"


def _honest_lines(result: StereoCalibration) -> list[str]:
    """The stereo held-out error and the RMS over all corners, escaped paragraphs."""
    out = []
    sol = result.solution
    if sol is not None and sol.corners_total:
        rejected = sum(a + b for _, a, b in sol.rejected_corners)
        out.append(f"RMS {sol.rms_px:.3f} px over the inlier corners, {sol.rms_all_px:.3f} px over all "
                   f"{sol.corners_total} ({rejected} rejected as outliers).")
    w = result.board_warp
    if w is not None:
        out.append(f"Board bend (mrcal-style parabola, at the board centre): x {w['warp_mm'][0]:+.3f} mm, y "
                   f"{w['warp_mm'][1]:+.3f} mm; {w['decision']}.")
    h = result.heldout
    if h is not None:
        out.append(f"Stereo held-out error {h.heldout_px:.3f} px on pairs left out of the fit ({h.folds} folds; one "
                   f"board pose per held-out pair fitted to both cameras); {h.heldout_all_px:.3f} px with the "
                   f"{h.corners_rejected} of {h.corners_total} corners left out as detector blunders.")
    return list(out)


def _std_table(result: StereoCalibration | MonoCalibration) -> str:
    h = result.heldout
    if h is None:
        return "<p class='note'>too few views for the jackknife: std from the covariance only</p>"
    rows = [[s.name, s.value, s.covariance, s.jackknife, s.source] for s in h.stds]
    return html_table(["parameter (px; baseline m; rotation deg)", "value", "std (covariance)",
                       f"std ({h.folds}-fold jackknife)", "reported"], rows,
                      caption="both standard deviations; the larger is reported and written to the profile",
                      left=[0, 4])


def _projection_section(projection: dict[str, dict[str, ProjectionMap | None]], size: tuple[int, int]
                        ) -> list[ReportSection]:
    """The projection uncertainty maps and their figures (none when neither map exists)."""
    if not any(m is not None for maps in projection.values() for m in maps.values()):
        return []
    rows = [[side, src, m.centre_px, m.corner_px] for side, maps in projection.items()
            for src, m in maps.items() if m is not None]
    return [ReportSection("Projection uncertainty", paragraphs=[(
        "How far a point seen at each pixel may land under other plausible calibrations (covariance draws, "
        "or the jackknife folds), after the camera rotation the board poses absorb; worst direction, px.")],
        images=[("projection uncertainty over the image (the larger of the two)",
                 projection_uncertainty(projection, size))],
        tables=[html_table(["camera", "from", "centre (px)", "worst image corner (px)"], rows, left=[0, 1])])]


def _stereo_sections(result: StereoCalibration) -> list[ReportSection]:
    p = result.profile
    q = p.provenance.calibration
    assert q is not None
    size = p.image_size
    rows = _camera_rows("left", p.left) + _camera_rows("right", p.right) + _extrinsic_rows(result)
    summary = ReportSection("Summary", paragraphs=[(
        f"Board: {result.board or _board(q.pattern, q.square_m)}. "
        f"{q.views_used} views used, {len(result.dropped)} skipped or dropped; lens model {q.distortion_terms}; "
        f"RMS left {q.rms_left_px:.3f} px, right {q.rms_right_px:.3f} px, stereo {q.rms_stereo_px:.3f} px; "
        f"epipolar RMS after rectification {result.epipolar_rms_px:.3f} px; baseline {p.baseline_m * 1000:.2f} mm. "
        "Convention: X_right = R X_left + T (metres).")] + _honest_lines(result)
        + [html_fragment("<span class='warn'>warning: {{ w }}</span>", w=w) for w in result.warnings],
        tables=[html_table(["parameter", "value", "std", "relative std"], rows), _std_table(result)])
    models = ReportSection("Lens model comparison", tables=[_models_table(result)])
    views = list(result.views)
    chart = _error_chart([v.name for v in views], {"left": [v.left_px for v in views],
                                                   "right": [v.right_px for v in views],
                                                   "stereo": [v.stereo_px for v in views]},
                         [v.used for v in views], result.threshold_px)
    corners = dict(zip(result.used_names, result.corners_left, strict=True))
    strip = thumbnail_strip([(v.name, corners.get(v.name), f"L {v.left_px:.2f} R {v.right_px:.2f} px"
                              + ("" if v.used else " dropped"), v.used) for v in views],
                            result.view_paths, size)
    errors = ReportSection("Per-view errors", images=[("per-view RMS; hatched red = dropped as outlier", chart),
                                                      ("every view (left image) with its error", strip)],
                           tables=[_views_table(result)])
    sections = [_verdict_section(result), summary, models, errors]
    if result.solution is not None:
        sol = result.solution
        sections.append(ReportSection("Residuals and board poses", images=[
            ("per-corner residual vectors over the image (magnified)", residual_vectors(
                {"left": result.corners_left, "right": result.corners_right},
                {"left": [r[0] for r in sol.residuals], "right": [r[1] for r in sol.residuals]}, size)),
            ("board poses in 3D", board_poses_3d(sol.rvecs, sol.tvecs,
                                                 board_object_points(q.pattern, q.square_m), p.R, p.T))]))
    sections += _projection_section(result.projection, size)
    sections.append(ReportSection("Coverage", paragraphs=[(
        f"board tilt {result.spread.tilt_deg[0]:.0f}-{result.spread.tilt_deg[1]:.0f} deg, distance "
        f"{result.spread.distance_m[0]:.2f}-{result.spread.distance_m[1]:.2f} m, board area "
        f"{100 * result.spread.size_fraction[0]:.0f}-{100 * result.spread.size_fraction[1]:.0f} % of the image")],
        images=[("views whose board covers each part of the image", coverage_maps(
            {"left": result.coverage_left, "right": result.coverage_right}, size))]))
    sample = _sample(result)
    if sample is not None and sample[1] is not None:
        sections.append(ReportSection("Detection and rectification", images=[
            ("detected corners (first used left image)", _overlay(sample[0], result.corners_left[0], q.pattern)),
            ("rectified pair with horizontal lines", _rectified_pair(result, sample[0], sample[1]))]))
    return sections


def _mono_sections(result: MonoCalibration) -> list[ReportSection]:
    cam = result.profile.camera
    q = result.profile.provenance.calibration
    assert q is not None
    h = result.heldout
    held = [] if h is None else [
        f"Held-out error {h.heldout_px:.3f} px over the corners of views left out of the fit ({h.folds} folds; one "
        f"board pose per held-out view), {h.heldout_all_px:.3f} px over all ({h.corners_rejected} of "
        f"{h.corners_total} corners in views beyond the training solve's threshold)."]
    summary = ReportSection("Summary", paragraphs=[(
        f"Board: {result.board or _board(q.pattern, q.square_m)}. "
        f"{q.views_used} views used, {len(result.dropped)} skipped or dropped; RMS {q.rms_left_px:.3f} px.")]
        + held + [html_fragment("<span class='warn'>warning: {{ w }}</span>", w=w) for w in result.warnings],
        tables=[html_table(["parameter", "value", "std", "relative std"], _camera_rows("camera", cam)),
                _std_table(result)])
    outliers = [d for d in result.dropped if d.rms_px is not None and d.reason.startswith("outlier")]
    names = list(result.view_names) + [d.name for d in outliers]
    errs = list(result.view_errors_px) + [float(d.rms_px) for d in outliers if d.rms_px is not None]
    used = [True] * len(result.view_names) + [False] * (len(names) - len(result.view_names))
    sections = [_verdict_section(result), summary,
                ReportSection("Lens model comparison", tables=[_models_table(result)]),
                ReportSection("Per-view errors", images=[
        ("per-view RMS", _error_chart(names, {"camera": errs}, used, result.threshold_px))],
        tables=[_dropped_table(result)]),
        ReportSection("Coverage", images=[("views whose board covers each part of the image", coverage_maps(
            {"camera": result.coverage}, result.profile.camera.image_size))])]
    sections += _projection_section(result.projection, result.profile.camera.image_size)
    sample = _sample(result)
    if sample is not None:
        sections.append(ReportSection("Detection", images=[
            ("detected corners", _overlay(sample[0], result.corners[0], q.pattern))]))
    return sections


def calibration_sections(result: StereoCalibration | MonoCalibration) -> list[ReportSection]:
    """The report's sections for a stereo or mono calibration."""
    return _mono_sections(result) if isinstance(result, MonoCalibration) else _stereo_sections(result)


def write_calibration_report(result: StereoCalibration | MonoCalibration, path: Path, *,
                             force: bool = False, batch: OutputBatch | None = None) -> Path:
    """Write the HTML report to ``path`` (atomic; refuses to overwrite unless ``force``), or stage it in
    ``batch`` to be published with the profile."""
    name = result.profile.name
    return write_report(path, f"s2r calibration: {name}", calibration_sections(result),
                        subtitle=result.profile.provenance.method, force=force, batch=batch)

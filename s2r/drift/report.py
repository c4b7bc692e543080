"""The HTML page of one drift check (``s2r check --report DIR``) and of a fleet (``s2r fleet check -o DIR``).

Every value goes through :mod:`s2r.htmlreport` (tables and plain-text paragraphs, escaped); figures are
matplotlib PNGs embedded as data URIs.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from s2r.drift.check import AXES, BLIND_SPOTS, CONVENTION, REGION_GRID, DriftResult
from s2r.htmlreport import ReportSection, figure_to_data_uri, html_table, render_report

__all__ = ["check_report_html", "fleet_report_html"]

_BANNER = {"good": "pass", "drifted": "fail", "cannot tell": "warn", "failed": "fail"}


def _figure(result: DriftResult) -> str:
    import matplotlib.pyplot as plt

    fig, (ax_map, ax_x) = plt.subplots(1, 2, figsize=(11.0, 3.8), layout="constrained")
    grid = np.array([[np.nan if v is None else v for v in row] for row in result.region_map_px], float)
    if grid.size == 0:
        grid = np.full(REGION_GRID, np.nan)
    w, h = result.image_size
    limit = max(0.5, float(np.nanmax(np.abs(grid))) if np.isfinite(grid).any() else 0.5)
    im = ax_map.imshow(grid, cmap="coolwarm", vmin=-limit, vmax=limit, extent=(0, w, h, 0))
    fig.colorbar(im, ax=ax_map, label="median vertical disparity (px)")
    ax_map.set_title("vertical disparity by image region (rectified left)", fontsize=9)
    ax_map.set_xlabel("x (px)")
    ax_map.set_ylabel("y (px)")
    left, dy = result.points.get("left", np.zeros((0, 2))), result.points.get("dy", np.zeros(0))
    ax_x.scatter(left[:, 0], dy, s=2, alpha=0.3, color="tab:blue")
    ax_x.axhline(0.0, color="k", linewidth=0.8)
    ax_x.set_ylim(-3 * limit, 3 * limit)
    ax_x.set_xlabel("x in the rectified left image (px)")
    ax_x.set_ylabel("right row - left row (px)")
    ax_x.set_title("every match: a slope is roll, an offset is pitch", fontsize=9)
    return figure_to_data_uri(fig)


def _sections(result: DriftResult, source: str) -> list[ReportSection]:
    verdict = ReportSection(
        "Verdict", banner=(_BANNER[result.verdict], f"{result.verdict.upper()}: {'; '.join(result.reasons)}"),
        paragraphs=[f"Recording: {source}. {result.matches} feature matches in {len(result.frames)} frames, "
                    f"robust residual {result.residual_px:.3f} px.", BLIND_SPOTS])
    rows = [[a, f"{o:+.4f}", f"{s:.4f}", f"{t:g}"] for a, o, s, t in
            zip(AXES, result.omega_deg, result.sigma_deg, result.tolerance_deg, strict=True)]
    estimators = [[name, *(f"{v:+.4f}" for v in values)] for name, values in result.estimators_deg.items()]
    rotation = ReportSection(
        "Relative rotation error", paragraphs=[CONVENTION, f"sigma: {result.sigma_source}.",
                                               f"Verdict decided by: {result.decided_by or 'nothing judged'}."],
        tables=[html_table(["axis", "error (deg)", "sigma (deg)", "tolerance (deg)"], rows),
                html_table(["estimator", *(f"{a} (deg)" for a in AXES)], estimators,
                           caption="Each estimator's rotation: sigma covers their disagreement")],
        images=[("vertical disparity of the matches", _figure(result))])
    cost_rows = [[f"{c['distance_m']:g}", f"{1000 * c['depth_error_m']:+.1f}", f"{c['depth_error_pct']:+.2f}",
                  f"{c['depth_error_sigma_pct']:.2f}"] for c in result.depth_cost]
    vertical = result.vertical_px
    cost = ReportSection(
        "What it costs", paragraphs=[
            f"Rows of mismatch the rotation leaves after rectification: median {vertical['median']:.2f} px, p95 "
            f"{vertical['p95']:.2f} px, max {vertical['max']:.2f} px (tolerance {result.tolerance_px:g} px p95). "
            "SGBM searches one row: past about 0.5 px matches fail or lock to the wrong texture."],
        tables=[html_table(["distance (m)", "depth error (mm)", "depth error (%)", "sigma (%)"], cost_rows,
                           caption="Depth bias at the image centre from the yaw part of the error")])
    frames = ReportSection("Frames", collapsed=True, tables=[html_table(
        ["frame", "matches", "keypoints", "sharpness (Laplacian variance)"],
        [[f["name"], f["matches"], f["keypoints"], f"{f['sharpness']:.0f}"] for f in result.frames])])
    return [verdict, rotation, cost, frames]


def check_report_html(result: DriftResult, *, source: str) -> str:
    """The self-contained page of one check."""
    return render_report(f"s2r check: {result.profile}", _sections(result, source),
                         subtitle="Is this stereo calibration still right? (target-less, from ordinary scenes)")


def fleet_report_html(rows: Sequence[dict[str, Any]], *, fleet_file: Path) -> str:
    """The fleet summary page: one row per robot, most severe first, each linking nothing (reports sit beside)."""
    table = html_table(
        ["robot", "verdict", "pitch (deg)", "yaw (deg)", "roll (deg)", "matches", "why", "report"],
        [[r["name"], r["verdict"], *(_axis(r, a) for a in AXES), r.get("matches", ""), "; ".join(r["reasons"]),
          r.get("report", "")] for r in rows],
        row_classes=[_BANNER.get(r["verdict"], "warn") for r in rows])
    counts = {v: sum(r["verdict"] == v for r in rows) for v in ("drifted", "failed", "cannot tell", "good")}
    banner = "pass" if counts["good"] == len(rows) else "fail" if counts["drifted"] or counts["failed"] else "warn"
    summary = ", ".join(f"{n} {v}" for v, n in counts.items() if n)
    return render_report("s2r fleet check", [ReportSection(
        "Fleet", banner=(banner, f"{len(rows)} robots: {summary}"), tables=[table],
        paragraphs=[f"Fleet file: {fleet_file}. Each robot's own report is in its folder. {BLIND_SPOTS}"])])


def _axis(row: dict[str, Any], axis: str) -> str:
    error = row.get("rotation_error_deg") or {}
    sigma = row.get("sigma_deg") or {}
    return f"{error[axis]:+.3f} +/- {sigma[axis]:.3f}" if axis in error else ""

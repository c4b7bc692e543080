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


def fleet_report_html(rows: Sequence[dict[str, Any]], *, fleet_file: Path, lost_workers: Sequence[str] = (),
                      resumed: Sequence[str] = (), trends: dict[str, dict[str, Any]] | None = None) -> str:
    """The fleet summary page: one row per robot, most severe first (each robot's report sits in its folder);
    the workers lost and the robots taken from an interrupted run; with ``trends`` (robot -> ``points`` and
    :func:`~s2r.drift.fleet_store.trend_summary`), each robot's rotation over the runs, one small plot each."""
    table = html_table(
        ["robot", "verdict", "pitch (deg)", "yaw (deg)", "roll (deg)", "matches", "why", "report"],
        [[r["name"], r["verdict"], *(_axis(r, a) for a in AXES), r.get("matches", ""), "; ".join(r["reasons"]),
          r.get("report", "")] for r in rows],
        row_classes=[_BANNER.get(r["verdict"], "warn") for r in rows])
    counts = {v: sum(r["verdict"] == v for r in rows) for v in ("drifted", "failed", "cannot tell", "good")}
    banner = "pass" if counts["good"] == len(rows) else "fail" if counts["drifted"] or counts["failed"] else "warn"
    summary = ", ".join(f"{n} {v}" for v, n in counts.items() if n)
    notes = [f"Fleet file: {fleet_file}. Each robot's own report is in its folder. {BLIND_SPOTS}"]
    if lost_workers:
        notes.append(f"{len(lost_workers)} Dask worker(s) lost during the run ({', '.join(lost_workers)}): their "
                     "robots were run again on the other workers.")
    if resumed:
        notes.append(f"{len(resumed)} robot(s) were taken from the interrupted run this one resumed.")
    sections = [ReportSection("Fleet", banner=(banner, f"{len(rows)} robots: {summary}"), tables=[table],
                              paragraphs=notes)]
    if trends:
        sections.append(_trend_section(rows, trends))
    return render_report("s2r fleet check", sections)


#: Robots given a trend plot on the page (the most severe first); the table covers every robot.
MAX_TREND_PLOTS = 200


def _days_text(value: Any) -> str:
    return "" if value is None else f"{value:.0f}" if value >= 10 else f"{value:.1f}"


def _trend_section(rows: Sequence[dict[str, Any]], trends: dict[str, dict[str, Any]]) -> ReportSection:
    names = [r["name"] for r in rows if r["name"] in trends]
    table = html_table(
        ["robot", "runs", *(f"{a} rate (deg/day)" for a in AXES), "days to tolerance (nearest axis)", "verdicts"],
        [[n, trends[n]["runs"], *(_rate(trends[n], a) for a in AXES), _days_text(_nearest(trends[n])),
          " ".join(_VERDICT_MARK.get(p.get("verdict"), "?") for p in trends[n]["points"])] for n in names],
        caption="Trend over the runs kept in the history (rate: least-squares line; days: at that rate, when it "
        "heads towards the tolerance)", left=[0, len(AXES) + 3])
    images = [(f"{n}: rotation error over the runs (deg)", _trend_figure(n, trends[n]["points"]))
              for n in names[:MAX_TREND_PLOTS] if len(trends[n]["points"]) >= 2]
    note = [f"Plots for the first {MAX_TREND_PLOTS} robots (most severe first)."] \
        if len(names) > MAX_TREND_PLOTS else []
    return ReportSection("Trend per robot", paragraphs=["Verdicts oldest first: G good, D drifted, ? cannot tell, "
                         "F failed. A slow drift shows as a rate before it crosses the tolerance.", *note],
                         tables=[table], images=images)


_VERDICT_MARK = {"good": "G", "drifted": "D", "cannot tell": "?", "failed": "F"}


def _rate(trend: dict[str, Any], axis: str) -> str:
    value = (trend.get("rate_deg_per_day") or {}).get(axis)
    return "" if value is None else f"{value:+.4f}"


def _nearest(trend: dict[str, Any]) -> float | None:
    days = [d for d in (trend.get("days_to_tolerance") or {}).values() if d is not None]
    return min(days) if days else None


def _trend_figure(name: str, points: Sequence[dict[str, Any]]) -> str:
    """A small plot: pitch, yaw and roll (deg) against the run, the tolerance as a band, drifted runs marked."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4.2, 1.9), layout="constrained")
    runs = np.arange(len(points))
    for axis, colour in zip(AXES, ("tab:blue", "tab:orange", "tab:green"), strict=True):
        values = [np.nan if p["rotation_error_deg"].get(axis) is None else p["rotation_error_deg"][axis]
                  for p in points]
        ax.plot(runs, values, marker="o", markersize=3, color=colour, label=axis)
    tolerance = [v for v in (points[-1].get("tolerance_deg") or {}).values() if isinstance(v, (int, float))]
    if tolerance:
        ax.axhspan(-max(tolerance), max(tolerance), color="0.9", zorder=0)
    for k, p in enumerate(points):
        if p.get("verdict") == "drifted":
            ax.axvline(k, color="tab:red", alpha=0.25, linewidth=3, zorder=0)
    ax.set_title(name, fontsize=8)
    ax.set_xticks(runs, [str(p["time"])[:10] for p in points], fontsize=6, rotation=30)
    ax.tick_params(axis="y", labelsize=6)
    ax.legend(fontsize=6, loc="upper left")
    return figure_to_data_uri(fig, dpi=80)


def _axis(row: dict[str, Any], axis: str) -> str:
    error = row.get("rotation_error_deg") or {}
    sigma = row.get("sigma_deg") or {}
    return f"{error[axis]:+.3f} +/- {sigma[axis]:.3f}" if axis in error else ""

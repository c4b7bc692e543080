"""Depth-quality figures as text lines and as a self-contained HTML report (verdict first, then the bins, the
metrics against distance with their theory lines, and every frame with its region of interest and depth)."""

from __future__ import annotations

from pathlib import Path

from s2r.errors import terminal_safe
from s2r.htmlreport import ReportSection, html_table, write_report
from s2r.quality.metrics import FrameQuality, not_scored
from s2r.quality.run import QualityResult
from s2r.quality.sanity import insane_reason
from s2r.quality.summary import BinQuality, QualityVerdict, quality_verdict

__all__ = ["BIN_HEADERS", "FRAME_HEADERS", "bin_rows", "frame_rows", "quality_lines", "quality_sections",
           "verdict_section", "write_quality_report"]

FRAME_HEADERS = ("image", "distance m", "Z accuracy %", "plane-fit RMS %", "sub-pixel RMS px", "fill rate %",
                 "outliers %", "scored", "note")
BIN_HEADERS = ("bin m", "frames", "not scored", "distance m", "Z accuracy %", "plane-fit RMS %", "sub-pixel RMS px",
               "fill rate %", "outliers %", "temporal noise %", "theory RMS % (0.08 px)")
_BANNER = {"good": "pass", "check": "warn", "poor": "fail"}


def _f(value: float | None, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def _guarded(frame: FrameQuality) -> FrameQuality:
    """The last guard before printing: a frame whose figures cannot be measurements is shown not scored."""
    reason = insane_reason(frame)
    return not_scored(frame, f"figure not a measurement: {reason}") if reason else frame


def frame_rows(frames: list[FrameQuality]) -> list[list[str]]:
    """One row per frame, formatted; a frame not scored says why in its note column, and a figure that cannot be
    a measurement (:func:`s2r.quality.sanity.insane_reason`) is never printed as one."""
    frames = [_guarded(f) for f in frames]
    return [[f.image, _f(f.distance_m, 3), _f(f.z_accuracy_pct), _f(f.plane_fit_rms_pct), _f(f.subpixel_rms_px, 3),
             _f(f.fill_rate_pct, 1), _f(f.outlier_pct, 1), "yes" if f.scored else "NO",
             "; ".join(filter(None, [f"not scored: {f.not_scored}" if f.not_scored else "", f.note]))]
            for f in frames]


def bin_rows(bins: list[BinQuality]) -> list[list[str]]:
    """One row per distance bin, formatted (medians over the scored frames)."""
    return [[f"{b.lo_m:g}-{b.hi_m:g}", str(b.frames), str(b.not_scored), _f(b.distance_m, 3), _f(b.z_accuracy_pct),
             _f(b.plane_fit_rms_pct), _f(b.subpixel_rms_px, 3), _f(b.fill_rate_pct, 1), _f(b.outlier_pct, 1),
             _f(b.temporal_noise_pct), _f(b.theory_rms_pct)] for b in bins]


def _table(headers: tuple[str, ...], rows: list[list[str]]) -> list[str]:
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(headers)]
    last = len(headers) - 1

    def line(cells: tuple[str, ...] | list[str]) -> str:
        parts = [c.ljust(w) if i == 0 else (c if i == last and headers[i] == "note" else c.rjust(w))
                 for i, (c, w) in enumerate(zip(cells, widths, strict=True))]
        return "  ".join(parts).rstrip()

    return [line(headers), *(line(r) for r in rows)]


def _datasheet_line(result: QualityResult) -> list[str]:
    ds = result.datasheet
    if ds is None:
        return []
    return [f"datasheet ({ds['source']}): Z accuracy <= {ds['z_accuracy_pct']:g} % and plane-fit RMS <= "
            f"{ds['plane_fit_rms_pct']:g} % at {ds['distance_m']:g} m over {ds['roi']}"]


def verdict(result: QualityResult) -> QualityVerdict:
    """The run's verdict (:func:`s2r.quality.summary.quality_verdict`)."""
    return quality_verdict(result.frames, result.datasheet)


def quality_lines(result: QualityResult) -> list[str]:
    """The terminal summary: verdict, per-frame table, per-bin table, temporal noise, datasheet figures."""
    v = verdict(result)
    lines = [f"depth quality of {terminal_safe(result.profile)} ({terminal_safe(result.source)}): "
             f"{v.level.upper()}: {v.headline}", *(f"  - {terminal_safe(r)}" for r in v.reasons)]
    lines += _table(FRAME_HEADERS, [[terminal_safe(c) for c in row] for row in frame_rows(result.frames)])
    lines += ["", "per distance bin (medians over the scored frames):", *_table(BIN_HEADERS, bin_rows(result.bins))]
    for t in result.temporal:
        lines.append(f"temporal noise of pose {t['pose_group']} ({t['frames']} frames at {t['distance_m']:.3f} m): "
                     f"{t['temporal_noise_pct']:.3f} % (Intel: per-pixel std / median depth, median over the ROI)")
    return lines + _datasheet_line(result)


def verdict_section(result: QualityResult, title: str = "Verdict") -> ReportSection:
    """The verdict as a banner section."""
    v = verdict(result)
    return ReportSection(title, paragraphs=[*v.reasons], banner=(_BANNER[v.level], f"{v.level.upper()}: {v.headline}"))


def quality_sections(result: QualityResult, title: str = "Depth quality") -> list[ReportSection]:
    """HTML sections: per-bin summary (with the datasheet line) and per-frame metrics."""
    paragraphs = [f"{result.profile}, {result.source}. Intel's definitions (rs-depth-quality): fill rate is valid "
                  "over ROI pixels; Z accuracy the median signed error of the plane-fit depth against the board's "
                  "PnP plane; plane-fit RMS and sub-pixel RMS (f B / Z - f B / Z_plane) after dropping the nearest "
                  "and farthest 0.5 % of the points. Mismatches (half a square or more off the board, or beyond 5 "
                  "robust sigmas of the plane) are counted as outliers and left out of both RMS figures; a frame "
                  "that cannot be scored says why."]
    paragraphs += _datasheet_line(result)
    return [ReportSection(title, paragraphs=paragraphs, tables=[html_table(BIN_HEADERS, bin_rows(result.bins))]),
            ReportSection(f"{title}: frames", tables=[html_table(FRAME_HEADERS, frame_rows(result.frames),
                                                                 row_classes=["" if f.scored else "warn"
                                                                              for f in result.frames],
                                                                 left=(len(FRAME_HEADERS) - 1,))])]


def _figure_sections(result: QualityResult) -> list[ReportSection]:
    from s2r.quality.plots import frame_figure, metric_figures

    by_name = {f.image: f for f in result.frames}
    frames = [(f"{im.name}: {'scored' if by_name.get(im.name) and by_name[im.name].scored else 'not scored'}",
               frame_figure(im, by_name.get(im.name))) for im in result.images]
    note = ([f"The first {len(result.images)} of {len(result.frames)} frames."]
            if len(result.images) < len(result.frames) else [])
    return [ReportSection("Metrics against distance", images=metric_figures(result)),
            ReportSection("Frames: region of interest (red) and depth", paragraphs=note, images=frames)]


def write_quality_report(result: QualityResult, folder: str | Path, *, force: bool = False) -> Path:
    """Write ``folder/depth_quality.html`` (verdict, bins, plots, frames); returns its path."""
    sections = [verdict_section(result), *quality_sections(result), *_figure_sections(result)]
    return write_report(Path(folder) / "depth_quality.html", f"Depth quality: {result.profile}", sections,
                        force=force)

"""Depth-quality figures as text lines and as a self-contained HTML report."""

from __future__ import annotations

from pathlib import Path

from s2r.errors import terminal_safe
from s2r.htmlreport import ReportSection, html_table, write_report
from s2r.quality.metrics import FrameQuality
from s2r.quality.run import QualityResult
from s2r.quality.summary import BinQuality

__all__ = ["FRAME_HEADERS", "bin_rows", "frame_rows", "quality_lines", "quality_sections", "write_quality_report"]

FRAME_HEADERS = ("image", "distance m", "Z accuracy %", "plane-fit RMS %", "sub-pixel RMS px", "fill rate %",
                 "outliers %", "note")
BIN_HEADERS = ("bin m", "frames", "distance m", "Z accuracy %", "plane-fit RMS %", "sub-pixel RMS px",
               "fill rate %", "temporal noise %", "theory RMS % (0.08 px)")


def _f(value: float | None, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def frame_rows(frames: list[FrameQuality]) -> list[list[str]]:
    """One row per frame, formatted."""
    return [[f.image, _f(f.distance_m, 3), _f(f.z_accuracy_pct), _f(f.plane_fit_rms_pct), _f(f.subpixel_rms_px, 3),
             _f(f.fill_rate_pct, 1), _f(f.outlier_pct, 1), f.note] for f in frames]


def bin_rows(bins: list[BinQuality]) -> list[list[str]]:
    """One row per distance bin, formatted."""
    return [[f"{b.lo_m:g}-{b.hi_m:g}", str(b.frames), _f(b.distance_m, 3), _f(b.z_accuracy_pct),
             _f(b.plane_fit_rms_pct), _f(b.subpixel_rms_px, 3), _f(b.fill_rate_pct, 1), _f(b.temporal_noise_pct),
             _f(b.theory_rms_pct)] for b in bins]


def _table(headers: tuple[str, ...], rows: list[list[str]]) -> list[str]:
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(headers)]
    line = "  ".join(h.rjust(w) if i else h.ljust(w) for i, (h, w) in enumerate(zip(headers, widths, strict=True)))
    out = [line]
    for r in rows:
        out.append("  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True))))
    return out


def _datasheet_line(result: QualityResult) -> list[str]:
    ds = result.datasheet
    if ds is None:
        return []
    return [f"datasheet ({ds['source']}): Z accuracy <= {ds['z_accuracy_pct']:g} % and plane-fit RMS <= "
            f"{ds['plane_fit_rms_pct']:g} % at {ds['distance_m']:g} m over {ds['roi']}"]


def quality_lines(result: QualityResult) -> list[str]:
    """The terminal summary: per-frame table, per-bin table, temporal noise, datasheet figures."""
    scored = sum(f.distance_m is not None for f in result.frames)
    lines = [f"depth quality of {terminal_safe(result.profile)} ({terminal_safe(result.source)}): "
             f"{scored}/{len(result.frames)} frames scored"]
    lines += _table(FRAME_HEADERS, [[terminal_safe(c) for c in row] for row in frame_rows(result.frames)])
    lines += ["", "per distance bin (medians over frames):", *_table(BIN_HEADERS, bin_rows(result.bins))]
    for t in result.temporal:
        lines.append(f"temporal noise of pose {t['pose_group']} ({t['frames']} frames at {t['distance_m']:.3f} m): "
                     f"{t['temporal_noise_pct']:.3f} %")
    return lines + _datasheet_line(result)


def quality_sections(result: QualityResult, title: str = "Depth quality") -> list[ReportSection]:
    """HTML sections: per-bin summary (with the datasheet line) and per-frame metrics."""
    paragraphs = [f"{result.profile}, {result.source}. Intel's camera depth testing methodology: Z accuracy is the "
                  "median signed error against the board's PnP plane, plane-fit RMS the RMS of residuals to the "
                  "best-fit plane, sub-pixel RMS those residuals in disparity pixels (f B dZ / Z^2)."]
    paragraphs += _datasheet_line(result)
    return [ReportSection(title, paragraphs=paragraphs, tables=[html_table(BIN_HEADERS, bin_rows(result.bins))]),
            ReportSection(f"{title}: frames", tables=[html_table(FRAME_HEADERS, frame_rows(result.frames))])]


def write_quality_report(result: QualityResult, folder: str | Path, *, force: bool = False) -> Path:
    """Write ``folder/depth_quality.html``; returns its path."""
    return write_report(Path(folder) / "depth_quality.html", f"Depth quality: {result.profile}",
                        quality_sections(result), force=force)

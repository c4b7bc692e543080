"""The recording comparison as terminal lines and as an HTML report section (sim and real per bin, with
bootstrap intervals and a verdict per bin)."""

from __future__ import annotations

from typing import Any, Protocol

from s2r.errors import terminal_safe
from s2r.htmlreport import ReportSection, html_table
from s2r.quality.report import BIN_HEADERS, FRAME_HEADERS, bin_rows, frame_rows, quality_sections
from s2r.validate.recording.compare import RecordingComparison

__all__ = ["WithRecording", "recording_lines", "recording_section", "recording_sections"]

_HEADERS = ("bin m", "frames real/sim", "not scored real/sim", "Z accuracy % real", "sim", "plane-fit RMS % real",
            "sim", "sub-pixel RMS px real", "sim", "fill % real", "sim", "outliers % real", "sim", "verdict")
_DIGITS = {"z_accuracy_pct": 2, "plane_fit_rms_pct": 2, "subpixel_rms_px": 3, "fill_rate_pct": 1, "outlier_pct": 1}


def _cell(value: float | None, ci: tuple[float, float] | None, digits: int) -> str:
    if value is None:
        return "-"
    text = f"{value:.{digits}f}"
    return text if ci is None else f"{text} [{ci[0]:.{digits}f}, {ci[1]:.{digits}f}]"


def _row(row: dict[str, Any]) -> list[str]:
    cells = [f"{row['lo_m']:g}-{row['hi_m']:g}", f"{row['real_frames']}/{row['sim_frames']}",
             f"{row.get('real_not_scored', 0)}/{row.get('sim_not_scored', 0)}"]
    by_metric = {m["metric"]: m for m in row.get("metrics", [])}
    for metric, digits in _DIGITS.items():
        m = by_metric.get(metric, {})
        cells += [_cell(m.get("real"), m.get("real_ci"), digits), _cell(m.get("sim"), m.get("sim_ci"), digits)]
    return [*cells, str(row.get("verdict", "ok" if row["passed"] else "FAIL"))]


def _sides(comparison: RecordingComparison) -> str:
    real_n = len(comparison.real.scored)
    sim_n = len(comparison.sim.scored)
    sim = (f"sim recording {comparison.sim_source}" if comparison.sim_source
           else "sim renders of the same boards at the recovered poses")
    return (f"real recording {comparison.folder} ({real_n}/{len(comparison.real.frames)} frames scored) vs {sim} "
            f"({sim_n}/{len(comparison.sim.frames)} scored); {comparison.pattern[0]}x{comparison.pattern[1]} board, "
            f"{comparison.square_m:g} m squares; Intel's metrics on each board's PnP plane, medians over scored "
            "frames [95 % bootstrap interval over frames]")


def recording_lines(comparison: RecordingComparison) -> list[str]:
    """Terminal lines: one side-by-side row per distance bin."""
    lines = [f"Recording: {terminal_safe(_sides(comparison))}:"]
    rows = [_row(r) for r in comparison.rows]
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(_HEADERS)]
    lines.append("  " + "  ".join(h.rjust(w) for h, w in zip(_HEADERS, widths, strict=True)))
    lines += ["  " + "  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    return lines


def _row_class(row: dict[str, Any]) -> str:
    return "warn" if row["passed"] is None else ("pass" if row["passed"] else "fail")


def recording_sections(comparison: RecordingComparison) -> list[ReportSection]:
    """HTML: the side-by-side table, then each side's per-bin and per-frame tables."""
    table = html_table(list(_HEADERS), [_row(r) for r in comparison.rows],
                       row_classes=[_row_class(r) for r in comparison.rows], left=(len(_HEADERS) - 1,))
    real_title = "Recording, real camera"
    sim_title = "Recording, sim camera" if comparison.sim_source else "Recording, sim renders"
    return [ReportSection("Recording: sim vs real per distance bin", paragraphs=[_sides(comparison) + "."],
                          tables=[table]),
            *quality_sections(comparison.real, real_title), *quality_sections(comparison.sim, sim_title)]


class WithRecording(Protocol):
    """What :func:`recording_section` reads of a run's result (a :class:`~s2r.validate.run.ValidationResult`,
    which is above this module)."""

    @property
    def recording(self) -> RecordingComparison | None: ...


def recording_section(result: WithRecording) -> ReportSection | None:
    """The validation report's one recording section (None without ``--recording``): the side-by-side table,
    then each side's per-bin and per-frame tables (captioned)."""
    if result.recording is None:
        return None
    comparison: RecordingComparison = result.recording
    head = recording_sections(comparison)[0]
    for side, quality in (("real", comparison.real), ("sim", comparison.sim)):
        head.paragraphs.append(f"{side}: {quality.profile}, {quality.source}")
        head.tables.append(html_table(BIN_HEADERS, bin_rows(quality.bins), caption=f"{side}: per distance bin"))
        head.tables.append(html_table(FRAME_HEADERS, frame_rows(quality.frames), caption=f"{side}: frames",
                                      row_classes=["" if f.scored else "warn" for f in quality.frames],
                                      left=(len(FRAME_HEADERS) - 1,)))
    return head

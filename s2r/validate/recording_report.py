"""The ``--recording`` comparison as terminal lines and as an HTML report section (sim and real per bin)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from s2r.errors import terminal_safe
from s2r.htmlreport import ReportSection, html_fragment, html_table
from s2r.quality.report import quality_sections
from s2r.validate.recording import RecordingComparison

if TYPE_CHECKING:
    from s2r.validate.run import ValidationResult

__all__ = ["recording_lines", "recording_section", "recording_sections"]

_HEADERS = ("bin m", "frames real/sim", "Z accuracy % real", "sim", "plane-fit RMS % real", "sim",
            "sub-pixel RMS px real", "sim", "fill % real", "sim", "verdict")

_EXTRA = ("<h3>{{ title }}</h3>{% for p in notes %}<p class='note'>{{ p }}</p>{% endfor %}"
          "{% for t in tables %}{{ t }}{% endfor %}")


def _f(value: float | None, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def _row(row: dict[str, Any]) -> list[str]:
    failed = [v["metric"].removesuffix("_pct").replace("_", " ") for v in row["verdicts"] if not v["passed"]]
    return [f"{row['lo_m']:g}-{row['hi_m']:g}", f"{row['real_frames']}/{row['sim_frames']}",
            _f(row["real_z_accuracy_pct"]), _f(row["sim_z_accuracy_pct"]), _f(row["real_plane_fit_rms_pct"]),
            _f(row["sim_plane_fit_rms_pct"]), _f(row["real_subpixel_rms_px"], 3), _f(row["sim_subpixel_rms_px"], 3),
            _f(row["real_fill_rate_pct"], 1), _f(row["sim_fill_rate_pct"], 1),
            "ok" if row["passed"] else "FAIL: " + ", ".join(failed)]


def recording_lines(comparison: RecordingComparison) -> list[str]:
    """Terminal lines: one side-by-side row per distance bin."""
    real_n = sum(f.distance_m is not None for f in comparison.real.frames)
    sim_n = sum(f.distance_m is not None for f in comparison.sim.frames)
    lines = [f"Recording {terminal_safe(comparison.folder)}: real camera on {real_n}/{len(comparison.real.frames)} "
             "boards, sim on "
             f"{sim_n} renders of the same poses (Intel's metrics on each board's PnP plane):"]
    rows = [_row(r) for r in comparison.rows]
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(_HEADERS)]
    lines.append("  " + "  ".join(h.rjust(w) for h, w in zip(_HEADERS, widths, strict=True)))
    lines += ["  " + "  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    return lines


def recording_sections(comparison: RecordingComparison) -> list[ReportSection]:
    """HTML: the side-by-side table, then each side's per-bin and per-frame tables."""
    table = html_table(list(_HEADERS), [_row(r) for r in comparison.rows],
                       row_classes=["pass" if r["passed"] else "fail" for r in comparison.rows])
    intro = (f"Boards of {comparison.pattern[0]}x{comparison.pattern[1]} inner corners, {comparison.square_m:g} m "
             f"squares, in {comparison.folder}: the real pairs through the real profile's pipeline; the same boards "
             "rendered at the recovered poses through the sim profile and the same pipeline and metrics.")
    return [ReportSection("Recording: sim vs real on the same boards", paragraphs=[intro], tables=[table]),
            *quality_sections(comparison.real, "Recording, real camera"),
            *quality_sections(comparison.sim, "Recording, sim renders")]


def recording_section(result: ValidationResult) -> ReportSection | None:
    """The validation report's one recording section (None without ``--recording``): the side-by-side table,
    then each side's per-bin and per-frame tables."""
    if result.recording is None:
        return None
    parts = recording_sections(result.recording)
    head = parts[0]
    for extra in parts[1:]:
        head.tables.append(html_fragment(_EXTRA, title=extra.title, notes=extra.paragraphs, tables=extra.tables))
    return head

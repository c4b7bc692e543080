"""The terminal summary of a validation run: plain text lines that fit one screen (about 40 lines)."""

from __future__ import annotations

import textwrap

from s2r.validate.advice.causes import RootCause
from s2r.validate.measures.params import ParamRow
from s2r.validate.run import ValidationResult

__all__ = ["summary_lines"]

_WIDTH = 110


def _value(value: float | str | None, digits: int = 5) -> str:
    if value is None:
        return "-"
    return value if isinstance(value, str) else f"{value:.{digits}g}"


def _param_lines(rows: list[ParamRow]) -> list[str]:
    lines = [f"  {'parameter':<22}{'sim':>14}{'real':>14}{'sim-real':>11}{'limit':>9}"]
    shown = [r for r in rows if not r.name.startswith("right ")]
    for r in shown:
        mark = "  FAIL" if r.exceeds_tolerance else ""
        sim, real = _value(r.sim), _value(r.real)
        if "distortion" in r.name:
            sim, real = sim.split(" ")[0] + ("" if "[0, 0" in sim else "*"), real.split(" ")[0]
        lines.append(f"  {r.name:<22}{sim:>14}{real:>14}{r.diff:>11.4g}{r.limit:>9.3g}{mark}")
    right_fail = [r.name for r in rows if r.name.startswith("right ") and r.exceeds_tolerance]
    lines.append(f"  right camera: {len(right_fail)} parameter(s) beyond tolerance"
                 + (f" ({', '.join(n[6:] for n in right_fail)})" if right_fail else ""))
    return lines


def _resolution_lines(result: ValidationResult) -> list[str]:
    lines = []
    for role, res in result.resolution.items():
        rms = " ".join(f"{z:g}m:{1000 * r:.1f}" for z, r in zip(res.distances_m, res.rms_m, strict=True))
        lines.append(f"  {role:<8} theory RMS mm {rms}; under 2 % up to {res.limit_2pct_m:.1f} m")
    return lines


def _recovery_lines(result: ValidationResult) -> list[str]:
    lines = []
    for role, rec in result.recovery.items():
        worst = max((r.n_sigma for r in rec.rows if r.n_sigma is not None), default=None)
        bad = [r.name for r in rec.rows if not r.passed]
        status = "all within tolerance" if not bad else f"FAIL {', '.join(bad)}"
        lines.append(f"  {role:<8} {rec.views_used}/{rec.views_rendered} views, RMS {_value(rec.rms_px, 3)} px, "
                     f"worst {_value(worst, 2)} sigma: {status}")
    return lines


def _depth_lines(result: ValidationResult) -> list[str]:
    roles = list(result.depth)
    head = f"  {'bin':<9}" + "".join(f"| {role[:7]:<7} med%  p90%  bias%  fill " for role in roles)
    lines = [head + "| theory% at far end, Intel 0.08 px / measured sub-pixel (" + "/".join(roles) + ")"
             + " | median 95% CI"]
    for i, b in enumerate(result.depth[roles[0]].bins):
        text = f"  {f'{b.lo_m:g}-{b.hi_m:g} m':<9}"
        for role in roles:
            s = result.depth[role].bins[i]
            fill = "-" if s.fill_rate is None else f"{s.fill_rate:.0%}"
            text += f"| {_value(s.median_pct, 3):>12} {_value(s.p90_pct, 3):>5} {_value(s.bias_pct, 2):>6} {fill:>5} "
        theory = "/".join(f"{result.depth[r].bins[i].theory_hi_pct or 0:.2f} / "
                          f"{_value(result.depth[r].bins[i].measured_theory_hi_pct, 2)}" for r in roles)
        ci = "/".join(f"{_value(result.depth[r].bins[i].ci_lo_pct, 2)}-{_value(result.depth[r].bins[i].ci_hi_pct, 2)}"
                      for r in roles)
        lines.append(text + f"| {theory} | {ci}")
    claim = ", ".join(f"{role} {_value(acc.within_3m.median_pct, 3)} % (p90 {_value(acc.within_3m.p90_pct, 3)} %, "
                      f"fill {acc.within_3m.fill_rate or 0:.0%})" for role, acc in result.depth.items())
    lines.append(f"  median |error| within 3 m, preset {result.settings.preset}: {claim}")
    subpx = ", ".join(f"{role} {_value(acc.subpixel_rms_px, 3)} px" for role, acc in result.depth.items())
    lines.append(f"  sub-pixel RMS measured (plane fit, Intel's definition): {subpx}; Intel's model uses 0.08 px")
    return lines


def _cause_lines(index: int, cause: RootCause) -> list[str]:
    lines = [f"  {index}. {cause.title}: {cause.what}"]
    effects = [c.name for c in cause.consequences]
    if effects:
        lines += textwrap.wrap(f"also fails: {', '.join(effects)}", width=_WIDTH, initial_indent=" " * 5,
                               subsequent_indent=" " * 7)
    lines += textwrap.wrap(f"fix: {cause.short_fix}", width=_WIDTH, initial_indent=" " * 5, subsequent_indent=" " * 7)
    return lines


def _verdict_lines(result: ValidationResult) -> list[str]:
    """PASS, or FAIL with the failures grouped by root cause, each with its consequences and its one edit."""
    if result.passed:
        return [f"PASS: all {len(result.checks)} checks within tolerance"]
    causes = result.root_causes
    what = "the sim differs from the real camera" if result.pair else "the profile fails its self-check"
    lines = [f"FAIL: {what}: {len(causes)} root cause(s) behind {len(result.failures)} failing checks (of "
             f"{len(result.checks)}); each with the checks it explains and the one edit that fixes it:"]
    for i, cause in enumerate(causes, 1):
        lines += _cause_lines(i, cause)
    return lines


def summary_lines(result: ValidationResult) -> list[str]:
    """The run as terminal lines: parameters, projection, resolution, recovery, depth, edits, verdict."""
    names = " vs ".join(f"{p.name} ({role})" for role, p in result.roles.items())
    s = result.settings
    drawn = "" if s.renderer == "pybullet" and not s.scene_path else f"rendered by {s.renderer}" + (
        f" in {s.scene_path}" if s.scene_path else "") + ", "
    lines = [f"s2r validate: {names}  [{drawn}{s.views} views at {s.supersample}x, scenes at {s.scene_supersample}x, "
             f"preset {s.preset}, seed {s.seed}]"]
    if result.pair:
        lines += ["Parameters:", *_param_lines(result.params)]
        proj = "; ".join(f"{d.camera} mean {d.mean_px:.3g} p95 {d.p95_px:.3g} px" for d in result.projection)
        lines.append(f"Projection difference at {result.tolerances.working_distance_m:g} m: {proj}")
        lines += [f"Note: {note}" for note in result.notes]
    lines += ["Depth resolution (Intel model):", *_resolution_lines(result)]
    if result.recovery:
        lines += ["Recovered calibration (rendered boards):", *_recovery_lines(result)]
    if result.depth:
        lines += ["Depth accuracy (rendered scenes, |relative error| by true depth):", *_depth_lines(result)]
    if result.recording is not None:
        from s2r.validate.recording.report import recording_lines

        lines += recording_lines(result.recording)
    lines += _verdict_lines(result)
    xml = [e for e in result.edits if e.parameter == "sensor XML"]
    mjcf = [e for e in result.edits if e.parameter == "MJCF cameras"]
    if xml:
        lines.append(f"  where to write each edit: --report, --json; every edit at once: {xml[0].where}")
        lines += [f"  MuJoCo: {e.where}" for e in mjcf]
    elif mjcf:  # a MuJoCo sim: its edits are MJCF <camera> attributes
        lines.append(f"  where to write each edit: --report, --json; every edit at once: {mjcf[0].where}")
    timing = ", ".join(f"{k} {v:.1f}s" for k, v in result.seconds.items() if k == "total")
    return [*lines, f"({timing})"]

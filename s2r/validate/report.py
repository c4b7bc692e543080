"""The HTML report of a validation run: one self-contained page (figures embedded) via :mod:`s2r.htmlreport`."""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from s2r.fileio import prepare_output_dir
from s2r.htmlreport import ReportSection, figure_to_data_uri, html_table, write_report
from s2r.validate.depth_accuracy import DepthAccuracy
from s2r.validate.run import ValidationResult

__all__ = ["REPORT_NAME", "build_sections", "write_validation_report"]

REPORT_NAME = "validation.html"


def _cls(passed: bool) -> str:
    return "pass" if passed else "fail"


def _verdict(result: ValidationResult) -> ReportSection:
    names = ", ".join(f"{role}: {p.name}" for role, p in result.roles.items())
    head = "PASS: every figure within tolerance" if result.passed else f"FAIL: {len(result.failures)} check(s)"
    section = ReportSection("Verdict", paragraphs=[f"<b>{html.escape(head)}</b> ({html.escape(names)})"])
    if result.failures:
        items = "".join(f"<li>{html.escape(c.text)}</li>" for c in result.failures)
        section.paragraphs.append(f"<ul>{items}</ul>")
    timing = ", ".join(f"{k} {v:.1f} s" for k, v in result.seconds.items())
    section.paragraphs.append(f"<span class='note'>Stage times: {html.escape(timing)}; settings "
                              f"{html.escape(str(result.settings.as_dict()))}</span>")
    return section


def _parameters(result: ValidationResult) -> ReportSection:
    rows = [[r.name, r.unit, r.sim, r.real, r.diff, r.limit, r.real_std, "yes" if r.exceeds_sigma else "",
             "FAIL" if r.exceeds_tolerance else "ok"] for r in result.params]
    table = html_table(["parameter", "unit", "sim", "real", "sim - real", "limit", "real std", "> 3 sigma", ""],
                       rows, row_classes=[_cls(not r.exceeds_tolerance) for r in result.params])
    return ReportSection("Parameters", tables=[table], paragraphs=[html.escape(n) for n in result.notes])


def _heat_map(diff: Any) -> str:
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    w, h = diff.image_size
    im = ax.imshow(diff.shift_px, extent=(-0.5, w - 0.5, h - 0.5, -0.5), cmap="viridis", aspect="equal")
    fig.colorbar(im, ax=ax, label="shift (px)")
    ax.set_title(f"{diff.camera} camera: projection difference at {diff.distance_m:g} m")
    ax.set_xlabel("u (px)")
    ax.set_ylabel("v (px)")
    return figure_to_data_uri(fig)


def _projection(result: ValidationResult) -> ReportSection:
    rows = [[d.camera, d.mean_px, d.p95_px, d.max_px, f"{d.outside_fraction:.0%}"] for d in result.projection]
    table = html_table(["camera", "mean (px)", "p95 (px)", "max (px)", "outside sim image"], rows)
    size = result.projection[0].image_size
    text = (f"Grid over the real left image ({size[0]}x{size[1]}); each pixel unprojected with the real camera at "
            f"{result.tolerances.working_distance_m:g} m and projected with the sim camera (scaled to the real "
            "resolution when sizes differ), as mrcal's projection difference.")
    return ReportSection("Projection difference", paragraphs=[text], tables=[table],
                         images=[(f"{d.camera} camera shift", _heat_map(d)) for d in result.projection])


def _resolution(result: ValidationResult) -> ReportSection:
    first = next(iter(result.resolution.values()))
    headers = ["profile", *[f"{z:g} m (mm)" for z in first.distances_m], "2% distance (m)", "matcher range (m)"]
    rows = [[f"{role}: {r.profile}", *[1000 * v for v in r.rms_m], r.limit_2pct_m, f"{r.near_m:.2f}-{r.far_m:.1f}"]
            for role, r in result.resolution.items()]
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    z = np.linspace(0.3, 6.0, 100)
    for role, profile in result.roles.items():
        ax.plot(z, 100 * profile.depth_rms_m(z) / z, label=f"{role}: {profile.name}")
    ax.axhline(2.0, color="grey", linestyle=":", label="2 %")
    ax.set_xlabel("depth (m)")
    ax.set_ylabel("theoretical RMS (% of depth)")
    ax.legend()
    return ReportSection("Depth resolution (Intel's model, s = 0.08 px)", tables=[html_table(headers, rows)],
                         images=[("theoretical relative depth RMS", figure_to_data_uri(fig))])


def _recovery(result: ValidationResult) -> ReportSection:
    section = ReportSection("Recovered calibration (PyBullet boards -> s2r calibrate)")
    for role, rec in result.recovery.items():
        section.paragraphs.append(f"<b>{html.escape(role)}: {html.escape(rec.profile)}</b>: {rec.views_used} of "
                                  f"{rec.views_rendered} views, stereo RMS {rec.rms_px or float('nan'):.3f} px")
        rows = [[r.name, r.unit, r.declared, r.recovered, r.error, r.std, r.n_sigma, r.floor,
                 "ok" if r.passed else "FAIL"] for r in rec.rows]
        section.tables.append(html_table(["parameter", "unit", "declared", "recovered", "error", "predicted std",
                                          "|error| / std", "floor", ""], rows,
                                         row_classes=[_cls(r.passed) for r in rec.rows]))
    return section


def _depth_figure(result: ValidationResult) -> str:
    fig, ax = plt.subplots(figsize=(6.8, 4.0))
    z = np.linspace(0.4, 5.2, 100)
    for i, (role, acc) in enumerate(result.depth.items()):
        colour = f"C{i}"
        scored = [b for b in acc.bins if b.median_pct is not None and b.p90_pct is not None]
        centres = [(b.lo_m + b.hi_m) / 2 for b in scored]
        ax.plot(centres, [float(b.median_pct or 0) for b in scored], "o-", color=colour, label=f"{role} median |error|")
        ax.plot(centres, [float(b.p90_pct or 0) for b in scored], "s--", color=colour, alpha=0.6,
                label=f"{role} p90 |error|")
        profile = result.roles[role]
        ax.plot(z, 100 * profile.depth_rms_m(z) / z, ":", color=colour, label=f"{role} theory RMS (Intel, 0.08 px)")
        if acc.subpixel_rms_px is not None:
            ax.plot(z, 100 * profile.depth_rms_m(z, acc.subpixel_rms_px) / z, "-.", color=colour, alpha=0.7,
                    label=f"{role} theory RMS (measured {acc.subpixel_rms_px:.3f} px)")
    ax.set_xlabel("depth (m)")
    ax.set_ylabel("relative depth error (%)")
    ax.legend(fontsize=8)
    return figure_to_data_uri(fig)


def _depth(result: ValidationResult) -> ReportSection:
    roles = list(result.depth)
    headers = ["bin"]
    for role in roles:
        headers += [f"{role} median %", f"{role} 95 % CI", f"{role} p90 %", f"{role} bias %", f"{role} fill",
                    f"{role} theory % (0.08 px)", f"{role} theory % (measured px)"]
    rows = []
    for i, b in enumerate(next(iter(result.depth.values())).bins):
        row: list[Any] = [f"{b.lo_m:g}-{b.hi_m:g} m"]
        for role in roles:
            s = result.depth[role].bins[i]
            ci = "-" if s.ci_lo_pct is None or s.ci_hi_pct is None else f"{s.ci_lo_pct:.2f}-{s.ci_hi_pct:.2f}"
            measured = ("-" if s.measured_theory_lo_pct is None or s.measured_theory_hi_pct is None
                        else f"{s.measured_theory_lo_pct:.2f}-{s.measured_theory_hi_pct:.2f}")
            row += [s.median_pct, ci, s.p90_pct, s.bias_pct, s.fill_rate,
                    f"{s.theory_lo_pct:.2f}-{s.theory_hi_pct:.2f}", measured]
        rows.append(row)
    within = "; ".join(f"{role}: median |error| within 3 m {_pct(acc.within_3m.median_pct)}, fill "
                       f"{_pct(100 * (acc.within_3m.fill_rate or 0))}" for role, acc in result.depth.items())
    acc0 = next(iter(result.depth.values()))
    subpx = "; ".join(f"{role} {acc.subpixel_rms_px:.3f} px" for role, acc in result.depth.items()
                      if acc.subpixel_rms_px is not None)
    text = (f"Preset {html.escape(acc0.preset)}, scenes {', '.join(acc0.scenes)}, planes at "
            f"{', '.join(f'{d:.3g}' for d in acc0.distances_m)} m (jittered per frame). {html.escape(within)}. "
            f"Measured sub-pixel RMS (plane fit): {html.escape(subpx or 'n/a')}; Intel's model uses 0.08 px.")
    return ReportSection("Depth accuracy (rendered ground truth, rectified left image)", paragraphs=[text],
                         tables=[html_table(headers, rows)],
                         images=[("depth error by distance beside the theoretical curve", _depth_figure(result))])


def _pct(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.2f} %"


def _show(ax: Any, image: Any, title: str, **kwargs: Any) -> Any:
    shown = ax.imshow(image[..., ::-1] if image.ndim == 3 else image, **kwargs)
    ax.set_title(title)
    ax.axis("off")
    return shown


def _samples_figure(role: str, acc: DepthAccuracy) -> str:
    s = acc.samples
    assert s is not None
    fig, axes = plt.subplots(1, 5, figsize=(17, 3.0))
    finite = s.truth_m[np.isfinite(s.truth_m)]
    lo, hi = (float(np.min(finite)), float(np.max(finite))) if finite.size else (0.0, 5.0)
    span = dict(cmap="turbo", vmin=lo - 0.05 * (hi - lo + 0.1), vmax=hi + 0.05 * (hi - lo + 0.1))
    _show(axes[0], s.left, "rendered left", cmap="gray")
    _show(axes[1], s.rect_left, "rectified left", cmap="gray")
    _show(axes[2], s.depth_m, "pipeline depth", **span)
    depth_im = _show(axes[3], s.truth_m, "true depth", **span)
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = 100.0 * (s.depth_m - s.truth_m) / s.truth_m
    err_im = _show(axes[4], rel, "relative error (%)", cmap="coolwarm", vmin=-2.0, vmax=2.0)
    fig.colorbar(depth_im, ax=axes[3], label="depth (m)", shrink=0.8)
    fig.colorbar(err_im, ax=axes[4], label="%", shrink=0.8)
    fig.suptitle(f"{role}: {acc.profile}, frame {s.name} (NaN = white/transparent)")
    return figure_to_data_uri(fig)


def _samples(result: ValidationResult) -> ReportSection:
    images = [(f"{role}: rendered, rectified, depth and ground truth", _samples_figure(role, acc))
              for role, acc in result.depth.items() if acc.samples is not None]
    return ReportSection("Sample images", images=images)


def _edits(result: ValidationResult) -> ReportSection:
    if not result.edits:
        return ReportSection("What to change", paragraphs=["Nothing: the sim parameters match within tolerance."])
    rows = [[e.parameter, e.current, e.target, e.where] for e in result.edits]
    table = html_table(["parameter", "now", "set to", "where"], rows)
    return ReportSection("What to change in the sim", tables=[table],
                         paragraphs=["Edits to the robot description that remove each parameter difference beyond "
                                     "tolerance; the sensor XML at the end of this page has them all."])


def _xml(result: ValidationResult) -> ReportSection:
    return ReportSection("Sensor XML for the real camera (s2r profile export-gazebo)",
                         paragraphs=[f"<pre>{html.escape(result.gazebo_xml or '')}</pre>"])


def build_sections(result: ValidationResult) -> list[ReportSection]:
    """The report's sections in reading order (pair-only sections left out of a self-check)."""
    sections = [_verdict(result)]
    if result.pair:
        sections += [_edits(result), _parameters(result), _projection(result)]
    sections.append(_resolution(result))
    if result.recovery:
        sections.append(_recovery(result))
    if result.depth:
        sections += [_depth(result), _samples(result)]
    if result.recording is not None:
        from s2r.validate.recording_report import recording_sections

        sections += recording_sections(result.recording)
    if result.gazebo_xml:
        sections.append(_xml(result))
    return sections


def write_validation_report(result: ValidationResult, out_dir: str | Path, *, force: bool = False) -> Path:
    """Write ``out_dir/validation.html`` (one self-contained page); returns its path.

    Raises:
        OutputExistsError: the folder holds files and ``force`` is false.
        S2RError: the folder cannot be created or written.
    """
    folder = prepare_output_dir(out_dir, force=force)
    title = "s2r validate: " + " vs ".join(p.name for p in result.roles.values())
    return write_report(folder / REPORT_NAME, title, build_sections(result),
                        subtitle="sim-to-real validation report", force=force)

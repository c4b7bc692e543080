"""The HTML report of a validation run: one self-contained page (figures embedded) via :mod:`s2r.htmlreport`."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from s2r.fileio import prepare_output_dir
from s2r.htmlreport import Markup, ReportSection, figure_to_data_uri, html_fragment, html_table, write_report
from s2r.validate.measures.depth_accuracy import DepthAccuracy
from s2r.validate.recording.report import recording_section
from s2r.validate.run import ValidationResult

__all__ = ["EXTRA_SECTIONS", "REPORT_NAME", "build_sections", "write_validation_report"]

REPORT_NAME = "validation.html"


def _cls(passed: bool) -> str:
    return "pass" if passed else "fail"


def _pct(value: float | None, digits: int = 2) -> str:
    """A percentage figure (already in percent) as text; ``n/a`` when missing."""
    return "n/a" if value is None else f"{value:.{digits}f} %"


def _fraction_pct(value: float | None) -> str:
    """A fraction (0..1) shown as a percentage."""
    return "n/a" if value is None else f"{100 * value:.1f} %"


def _banner(result: ValidationResult) -> tuple[str, Markup]:
    names = " vs ".join(f"{p.name} ({role})" for role, p in result.roles.items())
    causes = result.root_causes
    if result.passed:
        head = ("PASS: the sim is a faithful twin of the real camera" if result.pair
                else "PASS: the profile passes its self-check")
        return "pass", html_fragment(_BANNER, head=head, small=f"{names}: all {len(result.checks)} checks within "
                                     "tolerance")
    only_bench = all(c.key == "bench" for c in causes)
    if only_bench:
        return "warn", html_fragment(_BANNER, head="CHECK THE TEST BENCH: the sim-vs-real figures pass, the "
                                     "renderer/calibrator self-test does not", small=names)
    titles = ", ".join(c.title.lower() for c in causes if c.key != "bench")
    what = "the sim differs from the real camera in" if result.pair else "the profile fails on"
    return "fail", html_fragment(_BANNER, head=f"FAIL: {what} {titles}",
                                 small=f"{names}: {len(result.failures)} of {len(result.checks)} checks beyond "
                                 f"tolerance, explained by {len(causes)} root cause(s) below")


_BANNER = "{{ head }}<small>{{ small }}</small>"
_CAUSES = (
    "<table class='causes'><caption>Root causes: every failing check is listed once, under the parameter that "
    "explains it</caption><thead><tr>{% for h in headers %}<th class='text'>{{ h }}</th>{% endfor %}</tr></thead>"
    "<tbody>{% for cause in causes %}<tr class='fail'><td class='text'><b>{{ loop.index }}. {{ cause.title }}</b>"
    "</td><td class='text'>{{ cause.what }}</td><td class='text small'>{% if cause.consequences %}<ul>"
    "{% for c in cause.consequences %}<li>{{ c.text }}</li>{% endfor %}</ul>{% else %}-{% endif %}</td>"
    "<td class='text'>{{ cause.fix }}</td></tr>{% endfor %}</tbody></table>"
)


def _causes_table(result: ValidationResult) -> Markup:
    """Root causes as an HTML table: cause, what differs, the failing checks it explains, the one edit."""
    return html_fragment(_CAUSES, causes=result.root_causes,
                         headers=("root cause", "what differs (sim vs real)", "also fails because of it",
                                  "the one edit that fixes it"))


def _verdict(result: ValidationResult) -> ReportSection:
    section = ReportSection("Verdict", banner=_banner(result))
    if result.root_causes:
        section.tables.append(_causes_table(result))
    return section


def _settings(result: ValidationResult) -> ReportSection:
    s = result.settings
    scenes = "; ".join(f"{name} at {', '.join(f'{d:g}' for d in ds)} m" for name, ds in s.scenes)
    rows = [["board views (recovered calibration)", f"{s.views} at {s.supersample}x supersampling"],
            ["depth scenes", f"{scenes} ({s.scene_supersample}x supersampling)"],
            ["matcher preset", s.preset], ["random seed", str(s.seed)],
            *[[f"time: {k}", f"{v:.1f} s"] for k, v in result.seconds.items()]]
    return ReportSection("Run settings and stage times", collapsed=True,
                         tables=[html_table(["setting", "value"], rows, left=(0, 1), caption="How this run was made")])


def _parameters(result: ValidationResult) -> ReportSection:
    rows = [[r.name, r.unit, r.sim, r.real, r.diff, r.limit, r.real_std, "yes" if r.exceeds_sigma else "",
             "FAIL" if r.exceeds_tolerance else "ok"] for r in result.params]
    table = html_table(["parameter", "unit", "sim", "real", "sim - real", "limit |sim - real|", "real std",
                        "> 3 sigma", "verdict"], rows,
                       row_classes=[_cls(not r.exceeds_tolerance) for r in result.params],
                       caption="Sim and real parameters side by side (OpenCV 0-based pixels; each row in its unit)")
    return ReportSection("Parameters", tables=[table], paragraphs=list(result.notes))


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
    rows = [[d.camera, d.mean_px, d.p95_px, d.max_px, _fraction_pct(d.outside_fraction)] for d in result.projection]
    limit = result.tolerances.projection_p95_px
    table = html_table(["camera", "mean shift (px)", "p95 shift (px)", "max shift (px)",
                        "seen by real, outside sim image (%)"], rows,
                       row_classes=[_cls(d.p95_px <= limit) for d in result.projection],
                       caption=f"Pixel shift between where sim and real see the same point (p95 limit {limit:g} px)")
    size = result.projection[0].image_size
    text = (f"Grid over the real left image ({size[0]}x{size[1]} px); each pixel unprojected with the real camera at "
            f"{result.tolerances.working_distance_m:g} m and projected with the sim camera (scaled to the real "
            "resolution when sizes differ), as mrcal's projection difference.")
    return ReportSection("Projection difference", paragraphs=[text], tables=[table],
                         images=[(f"{d.camera} camera: pixel shift (px) over the real image", _heat_map(d))
                                 for d in result.projection])


def _legend_outside(ax: Any) -> None:
    """The legend beside the axes, so it never covers a curve or a point."""
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)


def _resolution(result: ValidationResult) -> ReportSection:
    first = next(iter(result.resolution.values()))
    headers = ["profile", *[f"RMS at {z:g} m (mm)" for z in first.distances_m], "2 % distance (m)",
               "matcher range (m)"]
    rows = [[f"{role}: {r.profile}", *[1000 * v for v in r.rms_m], r.limit_2pct_m, f"{r.near_m:.2f}-{r.far_m:.1f}"]
            for role, r in result.resolution.items()]
    fig, ax = plt.subplots(figsize=(7.4, 3.6))
    z = np.linspace(0.3, 6.0, 100)
    for role, profile in result.roles.items():
        ax.plot(z, 100 * profile.depth_rms_m(z) / z, label=f"{role}: {profile.name}")
    ax.axhline(2.0, color="grey", linestyle=":", label="2 %")
    ax.set_xlabel("depth (m)")
    ax.set_ylabel("theoretical RMS (% of depth)")
    _legend_outside(ax)
    table = html_table(headers, rows, caption="Theoretical depth RMS, Z^2 s / (fx B) with s = 0.08 px")
    return ReportSection("Depth resolution (Intel's model, s = 0.08 px)", tables=[table],
                         images=[("theoretical relative depth RMS (% of depth) against depth (m)",
                                  figure_to_data_uri(fig))])


def _recovery(result: ValidationResult) -> ReportSection:
    """The renderer/calibrator self-test: collapsible, after the answer (it says nothing about sim vs real)."""
    ok = all(rec.passed for rec in result.recovery.values())
    secs = sum(sum(rec.seconds.values()) for rec in result.recovery.values())
    section = ReportSection(
        f"The test bench itself: recovered calibration ({'passes' if ok else 'FAILS'})", collapsed=True,
        paragraphs=["PyBullet renders chessboards through each profile and s2r's own calibration must recover the "
                    "profile it rendered. This checks the renderer and the calibrator, not the sim against the "
                    "real camera: a failure here makes every figure above less certain, but needs no edit to the "
                    "sim." + (f" Its stages took {secs:.1f} s in all (profiles run in parallel)." if secs else "")])
    for role, rec in result.recovery.items():
        rows = [[r.name, r.unit, r.declared, r.recovered, r.error, r.std, r.n_sigma, r.floor,
                 "ok" if r.passed else "FAIL"] for r in rec.rows]
        caption = (f"{role} profile {rec.profile}: {rec.views_used} of {rec.views_rendered} views used, stereo RMS "
                   f"{rec.rms_px or float('nan'):.3f} px")
        section.tables.append(html_table(["parameter", "unit", "declared", "recovered", "error", "predicted std",
                                          "|error| / std", "floor", "verdict"], rows,
                                         row_classes=[_cls(r.passed) for r in rec.rows], caption=caption))
    return section


def _depth_figure(result: ValidationResult) -> str:
    fig, ax = plt.subplots(figsize=(7.8, 4.0))
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
    ax.set_xlabel("true depth (m)")
    ax.set_ylabel("relative depth error (% of depth)")
    _legend_outside(ax)
    return figure_to_data_uri(fig)


def _depth(result: ValidationResult) -> ReportSection:
    roles = list(result.depth)
    headers = ["true depth bin (m)"]
    for role in roles:
        headers += [f"{role} median |error| (%)", f"{role} median 95 % CI (%)", f"{role} p90 |error| (%)",
                    f"{role} bias (%)", f"{role} fill rate (%)", f"{role} theory RMS (%), Intel 0.08 px",
                    f"{role} theory RMS (%), measured sub-pixel"]
    rows = []
    for i, b in enumerate(next(iter(result.depth.values())).bins):
        row: list[Any] = [f"{b.lo_m:g}-{b.hi_m:g}"]
        for role in roles:
            s = result.depth[role].bins[i]
            ci = "-" if s.ci_lo_pct is None or s.ci_hi_pct is None else f"{s.ci_lo_pct:.2f}-{s.ci_hi_pct:.2f}"
            measured = ("-" if s.measured_theory_lo_pct is None or s.measured_theory_hi_pct is None
                        else f"{s.measured_theory_lo_pct:.2f}-{s.measured_theory_hi_pct:.2f}")
            row += [s.median_pct, ci, s.p90_pct, s.bias_pct, None if s.fill_rate is None else 100 * s.fill_rate,
                    f"{s.theory_lo_pct or 0:.2f}-{s.theory_hi_pct or 0:.2f}", measured]
        rows.append(row)
    within = "; ".join(f"{role}: median |error| within 3 m {_pct(acc.within_3m.median_pct)}, fill rate "
                       f"{_fraction_pct(acc.within_3m.fill_rate)}" for role, acc in result.depth.items())
    acc0 = next(iter(result.depth.values()))
    subpx = "; ".join(f"{role} {acc.subpixel_rms_px:.3f} px" for role, acc in result.depth.items()
                      if acc.subpixel_rms_px is not None)
    text = (f"Preset {acc0.preset}, scenes {', '.join(acc0.scenes)}, planes at "
            f"{', '.join(f'{d:.3g}' for d in acc0.distances_m)} m (jittered per frame). {within}. "
            f"Measured sub-pixel RMS (plane fit): {subpx or 'n/a'}; Intel's model uses 0.08 px.")
    table = html_table(headers, rows, caption="Depth error by true depth, as a percentage of the true depth")
    return ReportSection("Depth accuracy (rendered ground truth, rectified left image)", paragraphs=[text],
                         tables=[table],
                         images=[("relative depth error (%) by true depth (m), beside the theoretical RMS",
                                  _depth_figure(result))])


def _show(ax: Any, image: Any, title: str, **kwargs: Any) -> Any:
    shown = ax.imshow(image[..., ::-1] if image.ndim == 3 else image, **kwargs)
    ax.set_title(title)
    ax.axis("off")
    return shown


def _colour_bar(fig: Any, ax: Any, shown: Any, label: str) -> None:
    """A horizontal colour bar in an inset under ``ax``: it takes no width from the panel."""
    cax = ax.inset_axes((0.0, -0.14, 1.0, 0.05))
    fig.colorbar(shown, cax=cax, orientation="horizontal", label=label)


def _samples_figure(role: str, acc: DepthAccuracy) -> str:
    s = acc.samples
    assert s is not None
    fig, axes = plt.subplots(1, 5, figsize=(17, 3.6))
    finite = s.truth_m[np.isfinite(s.truth_m)]
    lo, hi = (float(np.min(finite)), float(np.max(finite))) if finite.size else (0.0, 5.0)
    span = dict(cmap="turbo", vmin=lo - 0.05 * (hi - lo + 0.1), vmax=hi + 0.05 * (hi - lo + 0.1))
    _show(axes[0], s.left, "rendered left", cmap="gray")
    _show(axes[1], s.rect_left, "rectified left", cmap="gray")
    _colour_bar(fig, axes[2], _show(axes[2], s.depth_m, "pipeline depth", **span), "depth (m)")
    _colour_bar(fig, axes[3], _show(axes[3], s.truth_m, "true depth", **span), "depth (m)")
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = 100.0 * (s.depth_m - s.truth_m) / s.truth_m
    shown = _show(axes[4], rel, "relative error", cmap="coolwarm", vmin=-2.0, vmax=2.0)
    _colour_bar(fig, axes[4], shown, "error (% of depth)")
    for ax in axes[:2]:
        ax.set_box_aspect(s.truth_m.shape[0] / s.truth_m.shape[1])
    fig.suptitle(f"{role}: {acc.profile}, frame {s.name} (NaN = white)")
    return figure_to_data_uri(fig)


def _samples(result: ValidationResult) -> ReportSection:
    images = [(f"{role} profile: rendered, rectified, pipeline depth, true depth and relative error (same scale)",
               _samples_figure(role, acc)) for role, acc in result.depth.items() if acc.samples is not None]
    return ReportSection("Sample images", images=images)


def _edits(result: ValidationResult) -> ReportSection:
    if not result.edits:
        return ReportSection("What to change", paragraphs=["Nothing: the sim parameters match within tolerance."])
    rows = [[e.parameter, e.current, e.target, e.where] for e in result.edits]
    table = html_table(["parameter", "now (sim)", "set to (real)", "where"], rows, left=(0, 1, 2, 3),
                       caption="Edits to the robot description, one per parameter beyond tolerance")
    return ReportSection("What to change in the sim", tables=[table],
                         paragraphs=["The sensor XML at the end of this page has them all."])


def _xml(result: ValidationResult) -> ReportSection:
    return ReportSection("Sensor XML for the real camera (s2r profile export-gazebo)",
                         paragraphs=[html_fragment("<pre>{{ xml }}</pre>", xml=result.gazebo_xml or "")])


#: Builders of further sections, shown after the answer and before the test bench (each returns None to skip).
#: Other validate stages (such as recordings) append theirs here.
EXTRA_SECTIONS: list[Callable[[ValidationResult], ReportSection | None]] = [recording_section]


def build_sections(result: ValidationResult) -> list[ReportSection]:
    """The report's sections in reading order: the answer first, then the details, then the test bench."""
    sections = [_verdict(result)]
    if result.pair:
        sections += [_edits(result), _parameters(result), _projection(result)]
    sections.append(_resolution(result))
    if result.depth:
        sections += [_depth(result), _samples(result)]
    sections += [s for s in (build(result) for build in EXTRA_SECTIONS) if s is not None]
    if result.gazebo_xml:
        sections.append(_xml(result))
    if result.recovery:
        sections.append(_recovery(result))
    sections.append(_settings(result))
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

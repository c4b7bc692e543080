"""``validate SIM REAL --recording SRC [--sim-recording SRC]``: the cameras measured on recordings, side by side.

``SRC`` is any input ``depth-quality`` takes (:mod:`s2r.quality.source`): folders or globs of stereo pairs, device
depth images, bag topics.

1. Real: every frame of the real recording through REAL (stereo pairs through its pipeline, or its device depth);
   Intel's metrics on each chessboard against its PnP plane (:mod:`s2r.quality`), and each board's pose.
2. Sim, from ``--sim-recording``: the sim camera's own recording (a Gazebo or MuJoCo recording of a board, or
   anything else ``SRC`` names) measured through SIM the same way. Without it, the same board (pattern, square
   size) is rendered at each recovered real pose, expressed in the left camera (``T_left_board = R1^T
   T_rect_board`` for stereo, R1 the real rectification; device depth is already in the left camera), through
   SIM, and the renders go through SIM's pipeline with the same preset and metrics.
3. Per distance bin, both sides side by side with bootstrap intervals and a verdict
   (:mod:`s2r.validate.recording.bins`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback
from s2r.quality.run import QualityResult, measure_board_views
from s2r.quality.source import RecordingSource, open_source, parse_source
from s2r.validate.recording.bins import compare_bins
from s2r.validate.tolerances import Tolerances
from s2r.validate.verdict import Check

__all__ = ["RecordingComparison", "check_recording_opens", "compare_recording", "compare_recordings",
           "recording_checks"]


@dataclass
class RecordingComparison:
    """Real and sim depth quality per bin; ``folder`` names the real recording, ``sim_source`` the sim's (None when
    the sim side is rendered at the recovered poses)."""

    folder: str
    pattern: tuple[int, int]
    square_m: float
    real: QualityResult
    sim: QualityResult
    rows: list[dict[str, Any]] = field(default_factory=list)
    sim_source: str | None = None

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON: ``real`` and ``sim`` each with ``bins`` and ``frames``, plus ``rows``."""
        return {"folder": self.folder, "real_source": self.folder, "sim_source": self.sim_source,
                "sim_mode": "recording" if self.sim_source else "rendered at the recovered poses",
                "pattern": list(self.pattern), "square_m": self.square_m,
                "real": self.real.as_dict(), "sim": self.sim.as_dict(), "rows": self.rows}


def _source(src: str | Path | RecordingSource, option: str) -> RecordingSource:
    return src if isinstance(src, RecordingSource) else parse_source(str(src), option=option)


def check_recording_opens(profile: StereoProfile, src: str | Path | RecordingSource, *, option: str,
                          preset: str) -> None:
    """Open the recording ``src`` for ``profile`` and read its first frame, before any render: a bag that is not
    one (``bag=/dev/null``), a missing topic, an unreadable or wrongly sized first image is refused in seconds,
    not after the renders (15-32 CPU-s). The comparison opens it again from the start.

    Raises:
        S2RError: what opening or reading the first frame raises; ValidateError when it holds no frame.
    """
    from s2r.errors import ValidateError

    source = _source(src, option)
    views = iter(open_source(profile, source, preset=preset).views)
    try:
        next(views)
    except StopIteration:
        raise ValidateError("the recording holds no frames", path=source.describe(), field=option,
                            hint="pass a recording with stereo pairs (or images and device depth)") from None
    finally:
        close = getattr(views, "close", None)
        if close is not None:
            close()


def _measure(profile: StereoProfile, source: RecordingSource, *, side: str, pattern: tuple[int, int],
             square_m: float, preset: str, progress: ProgressCallback | None
             ) -> tuple[QualityResult, NDArray[np.float64] | None]:
    opened = open_source(profile, source, preset=preset)
    result = measure_board_views(profile, opened.views, pattern=pattern, square_m=square_m,
                                 fb_px_m=opened.fb_px_m, source=f"{side} recording {source.describe()}, "
                                 f"{opened.description}", total=opened.total, visible_m=opened.visible_m,
                                 progress=progress)
    return result, opened.R1


def _left_poses(real: QualityResult, R1: NDArray[np.float64] | None) -> list[NDArray[np.float64] | None]:
    """Board poses in the real LEFT optical frame from poses in its rectified left frame (``R1``; None: already
    in the left frame)."""
    if R1 is None:
        return list(real.poses)
    rot = np.eye(4)
    rot[:3, :3] = R1.T
    return [None if T is None else rot @ T for T in real.poses]


def _rendered_sim(sim: StereoProfile, real_q: QualityResult, R1: NDArray[np.float64] | None, *, preset: str,
                  pattern: tuple[int, int], square_m: float, seed: int, progress: ProgressCallback | None,
                  renderer: tuple[str, str | None, str | None] = ("pybullet", None, None)) -> QualityResult:
    from s2r.depth.pipeline import StereoPipeline
    from s2r.quality.views import stereo_fb, stereo_view, stereo_visible_m
    from s2r.render.backend import RendererChoice
    from s2r.render.scenes import render_boards_at

    posed = [(f.image, T) for f, T in zip(real_q.frames, _left_poses(real_q, R1), strict=True) if T is not None]
    pairs = render_boards_at(sim, [T for _, T in posed], pattern=pattern, square_m=square_m, seed=seed, jobs=1,
                             progress=progress, renderer=RendererChoice(*renderer))
    pipe = StereoPipeline(sim, preset=preset)
    views = [stereo_view(pipe, name, left, right) for (name, _), (left, right) in zip(posed, pairs, strict=True)]
    return measure_board_views(sim, views, pattern=pattern, square_m=square_m, fb_px_m=stereo_fb(pipe),
                               source=f"sim renders of the recovered poses, preset {preset}",
                               visible_m=stereo_visible_m(pipe))


def compare_recording(sim: StereoProfile, real: StereoProfile, folder: str | Path | RecordingSource, *,
                      pattern: tuple[int, int], square_m: float, preset: str, tol: Tolerances, seed: int = 0,
                      progress: ProgressCallback | None = None,
                      renderer: tuple[str, str | None, str | None] = ("pybullet", None, None)) -> RecordingComparison:
    """Measure REAL on its recording ``folder`` (any ``SRC``) and SIM on renders of the same boards at the same
    poses (module docstring), drawn by ``renderer`` (name, MJCF world, world camera:
    :class:`s2r.render.backend.RendererChoice`)."""
    source = _source(folder, "--recording")
    real_q, R1 = _measure(real, source, side="real", pattern=pattern, square_m=square_m, preset=preset,
                          progress=progress)
    sim_q = _rendered_sim(sim, real_q, R1, preset=preset, pattern=pattern, square_m=square_m, seed=seed,
                          progress=progress, renderer=renderer)
    return RecordingComparison(source.describe(), pattern, square_m, real_q, sim_q,
                               compare_bins(real_q, sim_q, tol, seed=seed))


def compare_recordings(sim: StereoProfile, real: StereoProfile, *, sim_source: str | Path | RecordingSource,
                       real_source: str | Path | RecordingSource, pattern: tuple[int, int], square_m: float,
                       preset: str, tol: Tolerances, seed: int = 0,
                       progress: ProgressCallback | None = None) -> RecordingComparison:
    """Measure SIM on its own recording and REAL on its own, with the same metrics per bin (module docstring)."""
    real_src, sim_src = _source(real_source, "--recording"), _source(sim_source, "--sim-recording")
    real_q, _ = _measure(real, real_src, side="real", pattern=pattern, square_m=square_m, preset=preset,
                         progress=progress)
    sim_q, _ = _measure(sim, sim_src, side="sim", pattern=pattern, square_m=square_m, preset=preset,
                        progress=progress)
    return RecordingComparison(real_src.describe(), pattern, square_m, real_q, sim_q,
                               compare_bins(real_q, sim_q, tol, seed=seed), sim_source=sim_src.describe())


def recording_checks(comparison: RecordingComparison) -> list[Check]:
    """One check per bin and judged metric: sim minus real within its limit (missing sim figures fail). Bins
    without a scored real frame are shown in the table but make no check (nothing to compare against)."""
    out = []
    for row in comparison.rows:
        if row["passed"] is None:
            continue
        name = f"{row['lo_m']:g}-{row['hi_m']:g} m"
        for v in row["verdicts"]:
            label = v["metric"].removesuffix("_pct").replace("_", " ")
            unit = "px" if v["metric"].endswith("_px") else "% points"
            if v["gap"] is None:
                text = f"recording {name}: {label} missing on the {'sim' if row['sim_frames'] == 0 else 'real'} side"
                out.append(Check("recording", f"{label} gap {name}", "missing", v["limit"] or 0.0, unit, False, text))
                continue
            real, sim = row[f"real_{v['metric']}"], row[f"sim_{v['metric']}"]
            text = (f"recording {name}: {label} sim {sim:.3g} vs real {real:.3g} (gap {v['gap']:+.3g}, "
                    f"limit {v['limit']:.3g} {unit})")
            out.append(Check("recording", f"{label} gap {name}", v["gap"], v["limit"], unit, v["passed"], text))
    return out

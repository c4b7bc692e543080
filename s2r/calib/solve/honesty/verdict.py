"""A verdict a user can act on: good / check / poor, with the reasons, for a stereo calibration.

Each figure gets a level from fixed limits (pixels unless stated):

============================  ========  =========  ==============================================
figure                        good <=   check <=   beyond: poor
============================  ========  =========  ==============================================
stereo RMS reprojection       0.5       1.0
held-out RMS (chosen model)   0.6       1.2        also "check" above 2x the fitted RMS (stereo: pairs held out)
epipolar RMS (rectified)      0.5       1.0
baseline std / baseline       0.5 %     2 %
board footprint (coverage)    >= 50 %   >= 20 %    below 20 %: poor
============================  ========  =========  ==============================================

A better lens model on held-out views, unobservable parameters, dropped mismatched pairs and a joint solve
that stopped at its step limit still improving make it at least "check"; a lens model that cannot serve its
whole image (it folds over or overstretches inside it: :mod:`s2r.lens.fold`) makes it "poor". The
verdict is the worst level. One camera (``--mono``): the same RMS, held-out and coverage limits, and the
focal length's std relative to the focal length instead of the baseline's (good <= 0.5 %, check <= 2 %).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

__all__ = ["NOT_CONVERGED", "Reason", "Verdict", "mono_verdict", "stereo_verdict"]

Level = Literal["good", "check", "poor"]
#: The verdict's line and the warning when the joint solve stopped at its step limit still improving.
NOT_CONVERGED = ("the joint solve stopped at its step limit with the error still falling: the answer depends on "
                 "where it started, the views do not pin the lens model down; add views at varied tilt and "
                 "distance, or use fewer lens terms (--distortion k1k2)")
_ORDER = {"good": 0, "check": 1, "poor": 2}


@dataclass(frozen=True)
class Reason:
    """One judged figure: its level and a plain-language line."""

    level: Level
    text: str


@dataclass(frozen=True)
class Verdict:
    """The overall level (the worst reason's) and every reason."""

    level: Level
    reasons: tuple[Reason, ...]

    def as_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        return {"level": self.level, "reasons": [{"level": r.level, "text": r.text} for r in self.reasons]}


def _grade(value: float, good: float, check: float) -> Level:
    if not np.isfinite(value):
        return "check"
    return "good" if value <= good else "check" if value <= check else "poor"


def stereo_verdict(*, rms_px: float, heldout_px: float | None, epipolar_px: float, baseline_m: float,
                   baseline_std_m: float | None, coverage: Sequence[float], model_warning: str | None = None,
                   unobservable: Sequence[str] = (), mismatched: int = 0, heldout_over_all: bool = False,
                   converged: bool = True, lens_folds: Sequence[str] = ()) -> Verdict:
    """Judge a stereo calibration from its figures (see the module table); ``heldout_over_all``: the held-out
    error is over every corner (more were left out than detector blunders explain); ``converged`` False: the
    joint solve stopped at its step limit still improving; ``lens_folds``: a camera's lens model folds over
    inside its image (:func:`s2r.lens.fold.fold_warnings`), poor whatever the other figures say."""
    what = "stereo: pairs left out of the fit, one board pose per pair fitted to both cameras" + (
        "; over all corners: more than detector blunders fell beyond the blunder threshold" if heldout_over_all
        else "")
    reasons = [Reason(_grade(rms_px, 0.5, 1.0), f"stereo RMS reprojection error {rms_px:.3f} px"),
               *_heldout(heldout_px, rms_px, what)]
    reasons.append(Reason(_grade(epipolar_px, 0.5, 1.0), f"epipolar RMS after rectification {epipolar_px:.3f} px"))
    if baseline_std_m is None:
        reasons.append(Reason("check", "baseline uncertainty unknown"))
    else:
        rel = 100 * baseline_std_m / baseline_m
        reasons.append(Reason(_grade(rel, 0.5, 2.0), f"baseline {baseline_m * 1000:.2f} mm, std "
                                                      f"{baseline_std_m * 1000:.3g} mm ({rel:.2g} %)"))
    reasons += _common(coverage, model_warning, unobservable, lens_folds)
    if mismatched:
        reasons.append(Reason("check", f"{mismatched} mismatched pair(s) dropped"))
    if not converged:
        reasons.append(Reason("check", NOT_CONVERGED))
    level = max((r.level for r in reasons), key=lambda lv: _ORDER[lv])
    return Verdict(level, tuple(reasons))


def mono_verdict(*, rms_px: float, heldout_px: float | None, fx_px: float, fx_std_px: float | None,
                 coverage: float, model_warning: str | None = None, unobservable: Sequence[str] = (),
                 lens_folds: Sequence[str] = ()) -> Verdict:
    """Judge a single-camera calibration (see the module table; ``lens_folds`` as :func:`stereo_verdict`)."""
    reasons = [Reason(_grade(rms_px, 0.5, 1.0), f"RMS reprojection error {rms_px:.3f} px"),
               *_heldout(heldout_px, rms_px)]
    if fx_std_px is None:
        reasons.append(Reason("check", "focal length uncertainty unknown"))
    else:
        rel = 100 * fx_std_px / fx_px
        reasons.append(Reason(_grade(rel, 0.5, 2.0), f"fx {fx_px:.2f} px, std {fx_std_px:.2g} px ({rel:.2g} %)"))
    reasons += _common([coverage], model_warning, unobservable, lens_folds)
    level = max((r.level for r in reasons), key=lambda lv: _ORDER[lv])
    return Verdict(level, tuple(reasons))


def _heldout(heldout_px: float | None, rms_px: float, what: str = "views left out of the fit") -> list[Reason]:
    if heldout_px is None:
        return []
    level = _grade(heldout_px, 0.6, 1.2)
    if level == "good" and heldout_px > 2 * rms_px:
        level = "check"
    return [Reason(level, f"held-out error {heldout_px:.3f} px ({what})")]


def _common(coverage: Sequence[float], model_warning: str | None, unobservable: Sequence[str],
            lens_folds: Sequence[str] = ()) -> list[Reason]:
    worst = min(coverage) if coverage else 0.0
    cov_level: Level = "good" if worst >= 0.5 else "check" if worst >= 0.2 else "poor"
    out = [Reason(cov_level, "boards cover " + " / ".join(f"{100 * c:.0f} %" for c in coverage)
                  + " of the image" + ("" if cov_level == "good" else "; add views near the edges"))]
    if model_warning:
        out.append(Reason("check", model_warning))
    if unobservable:
        out.append(Reason("check", f"not observable from these views: {', '.join(unobservable)}"))
    out += [Reason("poor", fold) for fold in lens_folds]
    return out

"""Swapped cameras, as ``s2r calibrate`` refuses them: the right camera found to the LEFT of the left one.

Calibrate sees it in the board poses (:func:`s2r.calib.solve.solvers.rig.check_rig`); without a board the same fact
shows in the matches: rectified with the profile, a swapped pair's matches lie behind the rig (negative disparity) or
need a large turn to line up. Each way the recording could have been mixed up is tried on the raw SIFT matches
(no new detection: a 180-degree turn of an image moves a keypoint to ``(W - 1 - x, H - 1 - y)`` and SIFT is
rotation invariant):

- ``as given``;
- ``exchanged``: the left images are the right camera's and the other way round;
- ``upside down``: both images turned by 180 degrees (a rig mounted upside down, or a driver's flip);
- ``upside down and exchanged``.

A mix-up is named when it keeps clearly more matches in front of the rig than the recording as given, or as
many with a far smaller turn. An ideal rig (identical cameras, R = I) upside down looks exactly like one with its
cameras exchanged; then both are named.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from s2r.drift.matches import FrameMatches, RawMatches, gate_matches
from s2r.drift.model import fit_rotation
from s2r.profile import StereoProfile
from s2r.rectification import StereoRectification

__all__ = ["HYPOTHESES", "SwapFinding", "find_swap"]

FloatArray = NDArray[np.float64]
HYPOTHESES = ("as given", "exchanged", "upside down", "upside down and exchanged")
_FIX = {
    "exchanged": "give the left images as right and the right ones as left (the recording is mixed up, not the "
                 "profile: swapping the profile's cameras would put its right camera on the left)",
    "upside down": "turn both images by 180 degrees before checking (or use the profile of the rig as mounted)",
    "upside down and exchanged": "turn both images by 180 degrees and exchange left and right",
}


@dataclass(frozen=True)
class SwapFinding:
    """The mix-up found (one of :data:`HYPOTHESES`, never ``as given``), what it rests on, and the fix."""

    hypothesis: str
    alternative: str | None
    evidence: str
    fix: str

    def sentence(self) -> str:
        """One sentence for the verdict's reasons."""
        what = {"exchanged": "left and right look exchanged (the right camera sits to the LEFT of the left one)",
                "upside down": "the pair looks upside down (both images turned 180 degrees)",
                "upside down and exchanged": "the pair looks upside down and exchanged"}[self.hypothesis]
        also = f", or {self.alternative} (both fit alike)" if self.alternative else ""
        return f"{what}{also}: {self.evidence}; {self.fix}"


def _turned(points: FloatArray, size: tuple[int, int]) -> FloatArray:
    return np.column_stack([size[0] - 1 - points[:, 0], size[1] - 1 - points[:, 1]])


def mixed_up(raw: RawMatches, hypothesis: str) -> RawMatches:
    """The raw matches as they would be if the recording were mixed up by ``hypothesis`` (and put right)."""
    left, right = raw.left, raw.right
    if hypothesis.startswith("upside down"):
        left, right = _turned(left, raw.size), _turned(right, raw.size)
    if hypothesis.endswith("exchanged"):
        left, right = right, left
    return replace(raw, left=left, right=right)


def _score(profile: StereoProfile, rect: StereoRectification, raws: Sequence[RawMatches], hypothesis: str
           ) -> tuple[int, float]:
    """Matches kept in front of the rig under ``hypothesis``, and the size (deg) of the turn they need."""
    gated = [gate_matches(profile, rect, mixed_up(r, hypothesis)) for r in raws]
    left = np.vstack([g[0] for g in gated]) if gated else np.zeros((0, 2))
    right = np.vstack([g[1] for g in gated]) if gated else np.zeros((0, 2))
    if len(left) < 20:
        return len(left), float("inf")
    omega = fit_rotation(profile, rect, left, right, model="centre", nuisance=False).omega
    return len(left), float(np.degrees(np.linalg.norm(omega))) if np.all(np.isfinite(omega)) else float("inf")


def _better(given: tuple[int, float], other: tuple[int, float]) -> bool:
    """``other`` beats ``given``: clearly more matches in front, or as many with a far smaller turn."""
    (n0, turn0), (n1, turn1) = given, other
    if n1 >= max(1.5 * n0, n0 + 20):
        return True
    return n1 >= 0.8 * n0 and n1 >= 20 and turn0 > 0.3 and turn1 < 0.5 * turn0


def find_swap(profile: StereoProfile, rect: StereoRectification, frames: Sequence[FrameMatches]
              ) -> SwapFinding | None:
    """The mix-up the matches point to (module docstring), or None when the recording fits as given."""
    raws = [f.raw for f in frames if f.raw is not None and len(f.raw.left)]
    if not raws:
        return None
    scores = {h: _score(profile, rect, raws, h) for h in HYPOTHESES}
    given = scores["as given"]
    better = sorted((h for h in HYPOTHESES[1:] if _better(given, scores[h])),
                    key=lambda h: (-scores[h][0], scores[h][1]))
    if not better:
        return None
    best = better[0]
    n, turn = scores[best]
    rival = next((h for h in better[1:] if scores[h][0] >= 0.9 * n and scores[h][1] <= turn + 0.1), None)
    evidence = (f"{n} matches lie in front of the rig that way, with a {turn:.2f} deg turn, against {given[0]} as "
                f"given" + (f" with a {given[1]:.2f} deg turn" if np.isfinite(given[1]) else ""))
    return SwapFinding(best, rival, evidence, _FIX[best])

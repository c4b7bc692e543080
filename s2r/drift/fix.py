"""``s2r check --fix``: the profile with its relative rotation re-estimated, intrinsics and baseline kept, written
only when the verdict can be trusted and re-checked on frames the correction was not fitted on.

Refused (CheckError, one line): a swapped or upside-down recording, a "cannot tell" verdict, or fewer than 3
frames (nothing left to re-check on). The correction is fitted on two frames in three and changes only the axes
the check resolves (an unresolved yaw is kept as it was, and said); the corrected profile is then checked on the
remaining frames, and a correction those frames call drifted is not written.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from s2r.drift.check import AXES, Checked, CheckSettings, DriftResult, regated, summarise
from s2r.errors import CheckError
from s2r.profile import Extrinsics, StereoProfile

__all__ = ["Fix", "corrected_profile", "plan_fix"]

#: Frames needed: two in three fit the correction, the rest re-check it.
MIN_FIX_FRAMES = 3


@dataclass(frozen=True)
class Fix:
    """The corrected profile, the rotation applied (deg, zero on axes left alone), what was fitted and the
    re-check of the corrected profile on held-out frames."""

    profile: StereoProfile
    applied_deg: np.ndarray
    kept: list[str]
    fitted: DriftResult
    recheck: DriftResult
    held_out: list[str]

    def lines(self) -> list[str]:
        """What the fix did, for the terminal."""
        turned = ", ".join(f"{a} {o:+.4f}" for a, o in zip(AXES, self.applied_deg, strict=True))
        kept = f"; kept unchanged (not resolved): {', '.join(self.kept)}" if self.kept else ""
        r = self.recheck
        again = ", ".join(f"{a} {o:+.4f} +/- {s:.4f}" for a, o, s in zip(AXES, r.omega_deg, r.sigma_deg, strict=True))
        return [f"correction fitted on {len(self.fitted.frames)} frames: {turned} deg{kept}",
                f"re-checked on {len(self.held_out)} frames it did not fit ({', '.join(self.held_out[:5])}"
                f"{', ...' if len(self.held_out) > 5 else ''}): {r.verdict.upper()}, {again} deg"]


def corrected_profile(profile: StereoProfile, omega_deg: np.ndarray, *, note: str) -> StereoProfile:
    """``profile`` with ``R = dR @ R`` and ``T = dR @ T`` (the right camera turned about its own centre, so the
    baseline length is kept exactly), ``dR = exp(omega)``, omega in degrees about the right camera's axes; the
    provenance says how and from what it was corrected (``note``)."""
    dR = Rotation.from_rotvec(np.radians(omega_deg)).as_matrix()
    R = dR @ profile.R
    T = dR @ profile.T.reshape(3)
    extrinsics = Extrinsics(rotation=tuple(tuple(float(v) for v in row) for row in R),  # type: ignore[arg-type]
                            translation_m=tuple(float(v) for v in T),  # type: ignore[arg-type]
                            baseline_std_m=profile.extrinsics.baseline_std_m)
    notes = f"{profile.provenance.notes}; {note}" if profile.provenance.notes else note
    provenance = profile.provenance.model_copy(update={"method": f"{profile.provenance.method} + s2r check --fix",
                                                       "notes": notes})
    return profile.model_copy(update={"extrinsics": extrinsics, "provenance": provenance})


def _refuse_untrusted(result: DriftResult, frames: int) -> None:
    if result.swap is not None:
        raise CheckError("no correction written: the recording looks mixed up, not drifted", field="--fix",
                         hint=result.swap.fix)
    if result.verdict == "cannot tell":
        raise CheckError("no correction written: the check cannot tell the rotation", field="--fix",
                         hint="; ".join(result.reasons))
    if frames < MIN_FIX_FRAMES:
        raise CheckError(f"no correction written: {frames} frame(s), and a correction is re-checked on frames it "
                         f"was not fitted on", field="--fix", hint=f"record at least {MIN_FIX_FRAMES} pairs")


def plan_fix(checked: Checked, *, settings: CheckSettings, source: str) -> Fix:
    """The corrected profile of a trusted check, fitted on two frames in three and re-checked on the others."""
    _refuse_untrusted(checked.result, len(checked.frames))
    held = [k for k in range(len(checked.frames)) if k % 3 == 2]
    fit_frames = [f for k, f in enumerate(checked.frames) if k not in held]
    fitted = summarise(checked.profile, fit_frames, settings=settings, look_for_swap=False)
    if fitted.verdict == "cannot tell" or not np.all(np.isfinite(fitted.omega_deg)):
        raise CheckError("no correction written: the frames it would be fitted on cannot tell the rotation",
                         field="--fix", hint="; ".join(fitted.reasons))
    kept = [a for a in AXES if a in fitted.unresolved]
    applied = np.array([0.0 if a in kept else o for a, o in zip(AXES, fitted.omega_deg, strict=True)])
    turned = ", ".join(f"{a} {o:+.4f} +/- {s:.4f} deg" for a, o, s in
                       zip(AXES, applied, fitted.sigma_deg, strict=True))
    note = (f"relative rotation corrected by s2r check --fix from {fitted.matches} feature matches in "
            f"{len(fit_frames)} frames of {source} (target-less): R = dR @ R_before with {turned} about the right "
            f"camera's optical axes{'; kept: ' + ', '.join(kept) if kept else ''}; intrinsics and baseline length "
            "kept")
    profile = corrected_profile(checked.profile, applied, note=note)
    held_frames = regated(profile, [checked.frames[k] for k in held])
    recheck = summarise(profile, held_frames, settings=settings, look_for_swap=False)
    fix = Fix(profile, applied, kept, fitted, recheck, [f.name for f in held_frames])
    if recheck.verdict == "drifted":
        raise CheckError("no correction written: on the frames it was not fitted on, the corrected profile is "
                         f"still drifted ({'; '.join(recheck.reasons)})", field="--fix",
                         hint="record more frames of textured scenes, or recalibrate with a board")
    return fix

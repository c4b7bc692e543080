"""``s2r check --fix``: the profile with its relative rotation re-estimated, intrinsics and baseline kept."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from s2r.drift.check import AXES, DriftResult
from s2r.profile import Extrinsics, StereoProfile

__all__ = ["corrected_profile"]


def corrected_profile(profile: StereoProfile, result: DriftResult, *, source: str) -> StereoProfile:
    """``profile`` with ``R = dR @ R`` and ``T = dR @ T`` (the right camera turned about its own centre, so the
    baseline length is kept exactly); the provenance says how and from what it was corrected.

    Args:
        source: the recording, in words, for the provenance note.
    """
    dR = Rotation.from_rotvec(np.radians(result.omega_deg)).as_matrix()
    R = dR @ profile.R
    T = dR @ profile.T.reshape(3)
    extrinsics = Extrinsics(rotation=tuple(tuple(float(v) for v in row) for row in R),  # type: ignore[arg-type]
                            translation_m=tuple(float(v) for v in T),  # type: ignore[arg-type]
                            baseline_std_m=profile.extrinsics.baseline_std_m)
    turned = ", ".join(f"{a} {o:+.4f} +/- {s:.4f} deg" for a, o, s in
                       zip(AXES, result.omega_deg, result.sigma_deg, strict=True))
    note = (f"relative rotation corrected by s2r check --fix from {result.matches} feature matches in "
            f"{len(result.frames)} frames of {source} (target-less): R = dR @ R_before with {turned} about the right "
            "camera's optical axes; intrinsics and baseline length kept")
    notes = f"{profile.provenance.notes}; {note}" if profile.provenance.notes else note
    provenance = profile.provenance.model_copy(update={"method": f"{profile.provenance.method} + s2r check --fix",
                                                       "notes": notes})
    return profile.model_copy(update={"extrinsics": extrinsics, "provenance": provenance})

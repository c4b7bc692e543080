"""Real rigs against their own truth, and the injected-drift sweep (the figures of issue 38).

Rigs (../shared/data, recorded by others):
- ``webcam``: OpenCV's stereo chessboard set (a real USB webcam rig, 13 pairs, lenses with strong distortion), the
  profile ``s2r calibrate`` fits on it; truth: :mod:`tests.drift.board_anchor` (plain OpenCV on the corners);
- ``webcam-opencv``: the same images, profile from plain OpenCV (``calibrateCamera`` per camera, then
  ``stereoCalibrate`` with them fixed), so the profile itself shares no code with s2r; truth 0 by construction;
- ``cones``, ``teddy``, ``aloe``: Middlebury pairs, rectified by their makers: a pinhole profile with R = I; truth 0.

Injected drift: the profile's R is turned by ``delta`` about one axis of the right camera (R' = exp(delta) R),
so the rig really is at ``dR = exp(-delta)`` of the new profile, plus the profile's own truth. A check must call
the profile as given good, and never come back with the wrong sign and a confident verdict.

``python -m tests.drift.rig_sweep`` prints the tables (about a minute per rig on a loaded machine).
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.drift.check import AXES, CheckSettings, DriftResult, match_pairs, regated, summarise
from s2r.drift.matches import FrameMatches
from s2r.profile import Camera, Distortion, Extrinsics, Provenance, StereoProfile
from tests.drift.board_anchor import board_corners, board_drift_deg

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data"
WEBCAM = DATA / "opencv_stereo_chessboard"
DELTAS_DEG = (-0.5, -0.3, -0.1, 0.1, 0.3, 0.5)
Pair = tuple[str, NDArray[np.uint8], NDArray[np.uint8]]


@dataclass(frozen=True)
class Rig:
    """A real rig: its profile, its pairs and the drift truth of the profile (deg) with its sigma."""

    name: str
    profile: StereoProfile
    pairs: list[Pair]
    truth_deg: NDArray[np.float64]
    truth_sigma_deg: NDArray[np.float64]


def injected(profile: StereoProfile, delta_deg: NDArray[np.float64]) -> StereoProfile:
    """``profile`` with its right camera turned by ``delta_deg`` (rotation vector about the right camera's axes)."""
    dR = Rotation.from_rotvec(np.radians(delta_deg)).as_matrix()
    return profile.model_copy(update={"extrinsics": Extrinsics(
        rotation=tuple(tuple(float(v) for v in row) for row in dR @ profile.R),  # type: ignore[arg-type]
        translation_m=tuple(float(v) for v in dR @ profile.T.reshape(3)))})  # type: ignore[arg-type]


def _camera(K: NDArray[np.float64], D: NDArray[np.float64], size: tuple[int, int]) -> Camera:
    return Camera(width_px=size[0], height_px=size[1], fx_px=float(K[0, 0]), fy_px=float(K[1, 1]),
                  cx_px=float(K[0, 2]), cy_px=float(K[1, 2]),
                  distortion=Distortion(coefficients=tuple(float(v) for v in D.ravel()[:5])))


def _profile(name: str, left: Camera, right: Camera, R: NDArray[np.float64], T: NDArray[np.float64]) -> StereoProfile:
    return StereoProfile(name=name, left=left, right=right, extrinsics=Extrinsics(
        rotation=tuple(tuple(float(v) for v in row) for row in R),  # type: ignore[arg-type]
        translation_m=tuple(float(v) for v in T.reshape(3))),  # type: ignore[arg-type]
        provenance=Provenance(origin="real", method="tests.drift.rig_sweep", convention="opencv"))


def webcam_pairs() -> list[Pair]:
    """The 13 grey pairs of OpenCV's set, named by number."""
    out = []
    for path in sorted(WEBCAM.glob("left[0-9]*.jpg")):
        number = path.stem[4:]
        out.append((number, cv2.imread(str(path), cv2.IMREAD_GRAYSCALE),
                    cv2.imread(str(WEBCAM / f"right{number}.jpg"), cv2.IMREAD_GRAYSCALE)))
    return out


def opencv_webcam_rig() -> Rig:
    """The webcam set calibrated by plain OpenCV (no s2r code): truth 0 (the profile is the board's answer)."""
    left, right, size = board_corners(WEBCAM)
    grid = np.zeros((54, 3), np.float32)
    grid[:, :2] = np.mgrid[0:9, 0:6].T.reshape(-1, 2) * 0.025
    objects = [grid] * len(left)
    _, K1, D1, _, _ = cv2.calibrateCamera(objects, left, size, None, None)
    _, K2, D2, _, _ = cv2.calibrateCamera(objects, right, size, None, None)
    out = cv2.stereoCalibrate(objects, left, right, K1, D1, K2, D2, size, flags=cv2.CALIB_FIX_INTRINSIC)
    profile = _profile("webcam_opencv", _camera(K1, D1, size), _camera(K2, D2, size), out[5], out[6])
    _, sigma = board_drift_deg(K1, D1, K2, D2, out[5], WEBCAM)
    return Rig("webcam-opencv", profile, webcam_pairs(), np.zeros(3), sigma)


def s2r_webcam_rig(profile: StereoProfile) -> Rig:
    """The webcam set with the profile ``s2r calibrate`` fitted on it; truth from the board anchor."""
    truth, sigma = board_drift_deg(profile.left.K, profile.left.D, profile.right.K, profile.right.D, profile.R,
                                   WEBCAM)
    return Rig("webcam-s2r", profile, webcam_pairs(), truth, sigma)


def middlebury_rigs() -> Iterator[Rig]:
    """Middlebury's rectified pairs as pinhole rigs with R = I (f from a 60-degree field; it does not matter)."""
    for scene, left_name, right_name in (("cones", "im2.png", "im6.png"), ("teddy", "im2.png", "im6.png"),
                                         ("aloe", "aloeL.jpg", "aloeR.jpg")):
        folder = DATA / "middlebury" / scene
        left = cv2.imread(str(folder / left_name), cv2.IMREAD_GRAYSCALE)
        right = cv2.imread(str(folder / right_name), cv2.IMREAD_GRAYSCALE)
        h, w = left.shape
        f = w / (2 * np.tan(np.radians(30)))
        K = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1]])
        cam = _camera(K, np.zeros(5), (w, h))
        profile = _profile(scene, cam, cam, np.eye(3), np.array([-0.16, 0.0, 0.0]))
        yield Rig(scene, profile, [(scene, left, right)], np.zeros(3), np.zeros(3))


def sweep(rig: Rig, *, settings: CheckSettings | None = None) -> list[tuple[str, NDArray[np.float64], DriftResult]]:
    """The rig's check as given and with each injected drift: (label, truth deg, result). Matches once."""
    settings = settings or CheckSettings()
    frames: list[FrameMatches] = match_pairs(rig.profile, rig.pairs)
    rows = [("as given", rig.truth_deg, summarise(rig.profile, frames, settings=settings))]
    for axis in range(3):
        for delta in DELTAS_DEG:
            step = np.zeros(3)
            step[axis] = delta
            profile = injected(rig.profile, step)
            truth = rig.truth_deg - step  # to first order
            rows.append((f"{AXES[axis]} {delta:+.1f}", truth, summarise(profile, regated(profile, frames),
                                                                          settings=settings)))
    return rows


def wrong_and_confident(result: DriftResult, truth_deg: NDArray[np.float64], significance: float = 3.0) -> list[str]:
    """Axes reported with the wrong sign beyond ``significance`` sigmas, where the truth is itself clear of 0."""
    return [a for a, o, s, t in zip(AXES, result.omega_deg, result.sigma_deg, truth_deg, strict=True)
            if abs(t) >= 0.05 and np.sign(o) != np.sign(t) and abs(o) > significance * s]


def _print(rig: Rig) -> None:
    print(f"## {rig.name}: truth " + ", ".join(
        f"{a} {t:+.3f}+/-{s:.3f}" for a, t, s in zip(AXES, rig.truth_deg, rig.truth_sigma_deg, strict=True)))
    for label, truth, r in sweep(rig):
        got = ", ".join(f"{o:+.3f}+/-{s:.3f}" for o, s in zip(r.omega_deg, r.sigma_deg, strict=True))
        wrong = wrong_and_confident(r, truth)
        print(f"{label:<12} truth ({', '.join(f'{t:+.2f}' for t in truth)})  {r.verdict:<11} ({got}) "
              f"px p95 {r.vertical_px['p95']:.2f} {r.decided_by or '-'}{'  WRONG SIGN ' + str(wrong) if wrong else ''}")


if __name__ == "__main__":
    from s2r.registry import load_profile

    rigs = [s2r_webcam_rig(load_profile(sys.argv[1]))] if len(sys.argv) > 1 else []
    for rig in [*rigs, opencv_webcam_rig(), *middlebury_rigs()]:
        _print(rig)

"""Projection uncertainty of one pinhole camera (``--mono``): maps from the covariance and from the jackknife folds.

The covariance of (fx, fy, cx, cy, free distortion terms) is first-order, ``sigma^2 (J^T J)^-1`` with each
view's board pose eliminated (Schur complement) and ``sigma^2`` the residual variance, from
``cv2.projectPoints``' Jacobian at the solution. The maps themselves are :func:`s2r.calib.solve.honesty.projection.
projection_map`'s (pixels, worst direction, at 1 m).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.honesty.mono_resample import MonoHeldout
from s2r.calib.solve.honesty.projection import ProjectionMap, covariance_projection_map, projection_map
from s2r.calib.solve.solvers.cvsolve import MonoSolution
from s2r.lens.models import LENS_MODELS

__all__ = ["intrinsics_covariance", "mono_projection"]

FloatArray = NDArray[np.float64]
Points = NDArray[np.float32]


def intrinsics_covariance(obj: Sequence[Points], img: Sequence[Points], sol: MonoSolution,
                          free: Sequence[int]) -> FloatArray:
    """Covariance of (fx, fy, cx, cy, D[free]) (px^2 and coefficient^2) of the solution ``sol`` of the views
    ``obj``/``img`` (its board poses in the same order)."""
    cols = [6, 7, 8, 9, *(10 + i for i in free)]
    info = np.zeros((len(cols), len(cols)))
    ssr, m = 0.0, 0
    for o, p, rv, tv in zip(obj, img, sol.rvecs, sol.tvecs, strict=True):
        proj, jac = cv2.projectPoints(np.asarray(o, np.float64).reshape(-1, 1, 3), rv.reshape(3, 1), tv.reshape(3, 1),
                                      sol.K, sol.D)
        J = np.asarray(jac, np.float64)
        Jg, Jv = J[:, cols], J[:, 0:6]
        B = Jg.T @ Jv
        info += Jg.T @ Jg - B @ np.linalg.solve(Jv.T @ Jv, B.T)
        ssr += float(np.sum((np.asarray(proj, np.float64).reshape(-1, 2) - np.asarray(p, np.float64).reshape(-1, 2))
                            ** 2))
        m += 2 * len(o)
    sigma2 = ssr / max(1, m - len(cols) - 6 * len(obj))
    return np.asarray(sigma2 * np.linalg.pinv(info), np.float64)


def mono_projection(obj: Sequence[Points], img: Sequence[Points], sol: MonoSolution, held: MonoHeldout | None,
                    size: tuple[int, int], *, distortion: str) -> dict[str, ProjectionMap | None]:
    """The camera's projection uncertainty maps: ``covariance`` (:func:`intrinsics_covariance` propagated) and
    ``jackknife`` (the folds' intrinsics; None without resampling)."""
    free = LENS_MODELS[distortion].free
    try:
        cov = intrinsics_covariance(obj, img, sol, free)
    except np.linalg.LinAlgError:
        cov = np.full((4 + len(free), 4 + len(free)), np.nan)
    folds = [] if held is None else list(held.fold_intrinsics)
    return {"covariance": covariance_projection_map(sol.K, sol.D, size, cov, free),
            "jackknife": projection_map(sol.K, sol.D, size, folds)}

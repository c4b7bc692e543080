"""Calibration honesty on real stereo sets, beside plain OpenCV and mrcal, in one run (issue 22's bars).

Each set is given as ``NAME=FOLDER:COLSxROWS:SQUARE_M`` (FOLDER as ``s2r calibrate`` takes it: left/ and right/
subfolders or leftNN/rightNN images; COLSxROWS inner corners; SQUARE_M the square in metres). Per set:

- **s2r**: ``calibrate_stereo`` (jobs 2, corner cache in a temp folder), its ``--json`` figures.
- **Plain OpenCV** on its own detection: ``findChessboardCorners`` (ADAPTIVE_THRESH | NORMALIZE_IMAGE, no
  FAST_CHECK) + ``cornerSubPix`` (11x11), ``calibrateCamera`` per camera (k3 fixed) then ``stereoCalibrate``
  (USE_INTRINSIC_GUESS, k3 fixed: a joint refinement); over 4 interleaved folds of its pairs (pair i in fold
  i mod 4) the jackknife std ``sqrt((K-1)/K * sum_f (theta_f - mean)^2)`` of fx fy cx cy per camera and the
  baseline.
- **Boards**: every image where plain OpenCV finds the board must belong to a pair s2r used, or be listed in
  s2r's ``dropped`` with a reason.
- **Stereo held-out error**, computed here (no s2r code): the same 4 interleaved folds over s2r's used views;
  for each fold a model from the training views, then for every held-out pair ONE board pose fitted to both
  cameras' corners (scipy least_squares), RMS over all corners (px per corner, both coordinates:
  ``sqrt(mean(dx^2 + dy^2))``). Models: s2r's own (``calibrate_stereo`` re-run on the training pairs' images;
  the profile, a flat board, as a checker sees it; and with the fold's board warp when s2r used one), plain
  OpenCV's calibration on s2r's corners, and mrcal's (bench/mrcal_heldout.py, run with the system python that
  has Debian's python3-mrcal; both cameras jointly, flat and with mrcal's board warp). All on s2r's corners.
- **Repeated frames** (``--repeat``): the set again with every pair linked 3 times; s2r's reported std against
  the unique-view one.

Bars (issue 22): reported std / jackknife std in [0.5, 3] for >= 80 % of the 9 parameters; ``--json``'s
held-out error within 10 % of this script's; at most 3 % above mrcal's; no plain board lost; repeated-view std
within 15 % of the unique one.

Usage: nice -n 19 .venv/bin/python bench/bench_calib_realsets.py NAME=FOLDER:9x6:0.025 ... [--repeat]
       [--mrcal-python /usr/bin/python3] [--json OUT.json]
"""

from __future__ import annotations

import argparse
import json
import logging
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from s2r.calib import StereoCalibration, calibrate_stereo, find_stereo_pairs

Arr = NDArray[np.float64]
FOLDS = 4
NAMES9 = ("left fx", "left fy", "left cx", "left cy", "right fx", "right fy", "right cx", "right cy", "baseline")
PLAIN_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
SUBPIX = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
#: grey-level noise std of the second and third copy in the noisy repeat check.
REPEAT_NOISE = 2.0
MRCAL_SCRIPT = Path(__file__).resolve().with_name("mrcal_heldout.py")


@dataclass(frozen=True)
class SetSpec:
    """One real set: its name, folder, inner corners (cols, rows) and square (m)."""

    name: str
    folder: Path
    pattern: tuple[int, int]
    square: float


@dataclass(frozen=True)
class Model:
    """A stereo model in OpenCV's conventions (R, T map camera-0 points to camera 1, T in m) and the board
    points (N, 3) m it was fitted with (z = 0 for a flat board)."""

    K1: Arr
    D1: Arr
    K2: Arr
    D2: Arr
    R: Arr
    T: Arr
    board: Arr

    def params9(self) -> Arr:
        """fx fy cx cy of both cameras (px) and the baseline (m)."""
        k1, k2 = self.K1, self.K2
        return np.array([k1[0, 0], k1[1, 1], k1[0, 2], k1[1, 2], k2[0, 0], k2[1, 1], k2[0, 2], k2[1, 2],
                         float(np.linalg.norm(self.T))])


def parse_spec(text: str) -> SetSpec:
    """``NAME=FOLDER:COLSxROWS:SQUARE_M``."""
    try:
        name, rest = text.split("=", 1)
        folder, pat, square = rest.rsplit(":", 2)
        cols, rows = (int(v) for v in pat.lower().split("x"))
        return SetSpec(name, Path(folder), (cols, rows), float(square))
    except ValueError as exc:
        raise SystemExit(f"error: {text}: expected NAME=FOLDER:COLSxROWS:SQUARE_M ({exc})") from None


def board_points(pattern: tuple[int, int], square: float, warp: Sequence[float] | None = None) -> Arr:
    """Board corners (N, 3) m in OpenCV's chessboard order (x along the cols); ``warp`` (m) bends the board
    as mrcal does: z = wx * (1 - u^2) + wy * (1 - v^2), u and v from -1 to 1 across the board."""
    cols, rows = pattern
    yy, xx = np.mgrid[0:rows, 0:cols]
    pts = np.zeros((rows * cols, 3))
    pts[:, 0] = xx.reshape(-1) * square
    pts[:, 1] = yy.reshape(-1) * square
    if warp is not None:
        u = 2 * xx.reshape(-1) / (cols - 1) - 1
        v = 2 * yy.reshape(-1) / (rows - 1) - 1
        pts[:, 2] = warp[0] * (1 - u ** 2) + warp[1] * (1 - v ** 2)
    return pts


def plain_detect(path: Path, pattern: tuple[int, int]) -> tuple[Arr | None, tuple[int, int]]:
    """Plain OpenCV detection: the corners (N, 2) px or None, and the image size (w, h)."""
    grey = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    size = (grey.shape[1], grey.shape[0])
    ok, c = cv2.findChessboardCorners(grey, pattern, flags=PLAIN_FLAGS)
    if not ok:
        return None, size
    c = cv2.cornerSubPix(grey, c, (11, 11), (-1, -1), SUBPIX)
    return c.reshape(-1, 2).astype(np.float64), size


def opencv_model(left: Sequence[Arr], right: Sequence[Arr], board: Arr, size: tuple[int, int]) -> Model:
    """calibrateCamera per camera (k3 fixed), then stereoCalibrate refining all jointly (k3 fixed)."""
    obj = [board.astype(np.float32)] * len(left)
    pl = [c.astype(np.float32).reshape(-1, 1, 2) for c in left]
    pr = [c.astype(np.float32).reshape(-1, 1, 2) for c in right]
    _, k1, d1, _, _ = cv2.calibrateCamera(obj, pl, size, None, None, flags=cv2.CALIB_FIX_K3)
    _, k2, d2, _, _ = cv2.calibrateCamera(obj, pr, size, None, None, flags=cv2.CALIB_FIX_K3)
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-7)
    out = cv2.stereoCalibrate(obj, pl, pr, k1, d1, k2, d2, size, criteria=crit,
                              flags=cv2.CALIB_USE_INTRINSIC_GUESS | cv2.CALIB_FIX_K3)
    return Model(out[1], out[2].reshape(-1), out[3], out[4].reshape(-1), out[5], out[6].reshape(3), board)


def heldout_sq(model: Model, left: Sequence[Arr], right: Sequence[Arr]) -> Arr:
    """Squared errors (px^2, dx^2 + dy^2 per corner) of held-out pairs: one board pose per pair, fitted to
    both cameras' corners together with the model fixed."""
    rvec2, _ = cv2.Rodrigues(model.R)
    t2 = model.T.reshape(3, 1)
    out = []
    for cl, cr in zip(left, right, strict=True):
        def residual(x: Arr, cl: Arr = cl, cr: Arr = cr) -> Arr:
            a = cv2.projectPoints(model.board, x[:3], x[3:], model.K1, model.D1)[0].reshape(-1, 2) - cl
            r3, t3 = cv2.composeRT(x[:3].reshape(3, 1), x[3:].reshape(3, 1), rvec2, t2)[:2]
            b = cv2.projectPoints(model.board, r3, t3, model.K2, model.D2)[0].reshape(-1, 2) - cr
            return np.concatenate([a, b]).reshape(-1)

        _, rv, tv = cv2.solvePnP(model.board, cl.reshape(-1, 1, 2), model.K1, model.D1)
        x = least_squares(residual, np.concatenate([rv.reshape(3), tv.reshape(3)]), method="lm").x
        out.append(np.sum(residual(x).reshape(-1, 2) ** 2, axis=1))
    return np.concatenate(out)


def folds_of(n: int) -> list[list[int]]:
    return [list(range(f, n, FOLDS)) for f in range(FOLDS)]


def jackknife(thetas: Sequence[Arr]) -> Arr:
    t = np.asarray(thetas)
    k = len(t)
    return np.asarray(np.sqrt((k - 1) / k * np.sum((t - t.mean(axis=0)) ** 2, axis=0)))


def rms(sq: Sequence[Arr]) -> float:
    return float(np.sqrt(np.mean(np.concatenate(sq))))


def run_s2r(left: Sequence[Path], right: Sequence[Path], names: Sequence[str], spec: SetSpec,
            cache: Path, **kw: Any) -> StereoCalibration:
    return calibrate_stereo(list(left), list(right), names=list(names), pattern=spec.pattern,
                            square_m=spec.square, jobs=2, cache_dir=cache, **kw)


def s2r_model(res: StereoCalibration, board: Arr) -> Model:
    p = res.profile
    return Model(p.left.K, p.left.D, p.right.K, p.right.D, np.asarray(p.R, float),
                 np.asarray(p.T, float).reshape(3), board)


def board_check(pairs: Any, plain: list[tuple[Arr | None, Arr | None]], res: StereoCalibration) -> dict[str, Any]:
    """Images where plain OpenCV finds a board: used by s2r, listed as dropped (with the reason), or lost."""
    used = set(res.used_names)
    found, listed, lost = 0, [], []
    for name, (cl, cr), lp, rp in zip(pairs.names, plain, pairs.left, pairs.right, strict=True):
        for corners, path in ((cl, lp), (cr, rp)):
            if corners is None:
                continue
            found += 1
            if name in used:
                continue
            why = [d.reason for d in res.dropped if d.name == name or Path(path).name in d.name]
            (listed if why else lost).append(f"{Path(path).name}: {why[0] if why else 'not used, not listed'}")
    return {"plain_boards": found, "images": 2 * len(pairs.names), "listed": listed, "lost": lost}


def s2r_fold_models(pairs: Any, res: StereoCalibration, spec: SetSpec, cache: Path,
                    board: Arr) -> tuple[list[Model | None], list[Model | None], list[str]]:
    """s2r re-run on each fold's training pairs: the profile (flat board) and, when that run chose the board
    warp, the same with its warp."""
    idx = {n: i for i, n in enumerate(pairs.names)}
    flat: list[Model | None] = []
    warped: list[Model | None] = []
    notes = []
    for test in folds_of(len(res.used_names)):
        train = [n for j, n in enumerate(res.used_names) if j not in set(test)]
        sel = [idx[n] for n in train]
        try:
            r = run_s2r([pairs.left[i] for i in sel], [pairs.right[i] for i in sel], train, spec, cache,
                        compare=False)
        except Exception as exc:  # s2r's own errors, and any crash: reported, the run goes on
            notes.append(f"fold failed: {_why(exc)}")
            flat.append(None)
            warped.append(None)
            continue
        flat.append(s2r_model(r, board))
        bw = r.board_warp
        if bw is not None and bw.get("used"):
            wb = board_points(spec.pattern, spec.square, [v / 1000 for v in bw["warp_mm"]])
            warped.append(s2r_model(r, wb))
        else:
            warped.append(flat[-1])
    return flat, warped, notes


def fold_sq(models: Sequence[Model | None], left: Sequence[Arr], right: Sequence[Arr]) -> Arr | None:
    """Every held-out corner's squared error (px^2) over the folds, or None when a fold has no model."""
    if any(m is None for m in models):
        return None
    return np.concatenate([heldout_sq(m, [left[i] for i in test], [right[i] for i in test])
                           for m, test in zip(models, folds_of(len(left)), strict=True) if m is not None])


def fold_heldout(models: Sequence[Model | None], left: Sequence[Arr], right: Sequence[Arr]) -> float | None:
    """The stereo held-out RMS (px) over all corners."""
    sq = fold_sq(models, left, right)
    return None if sq is None else rms([sq])


def trimmed(sq: Arr | None) -> tuple[float | None, int]:
    """RMS (px) without the corners beyond the median + 5 robust sigmas (at least 0.3 px), and their count."""
    if sq is None:
        return None, 0
    e = np.sqrt(sq)
    med = float(np.median(e))
    thr = max(med + 5 * 1.4826 * float(np.median(np.abs(e - med))), 0.3)
    return rms([sq[e <= thr]]), int(np.sum(e > thr))


def run_mrcal(python: str, res: StereoCalibration, left: Sequence[Arr], right: Sequence[Arr], spec: SetSpec,
              size: tuple[int, int], tmp: Path) -> dict[str, Any]:
    """mrcal's fold models on s2r's corners (a subprocess of the system python), scored here."""
    n = len(left)
    masks = np.array([np.isin(np.arange(n), f) for f in folds_of(n)])
    p = res.profile
    inp, out = tmp / "mrcal_in.npz", tmp / "mrcal_out.npz"
    np.savez(inp, left=np.array(left), right=np.array(right), pattern=np.array(spec.pattern), square=spec.square,
             size=np.array(size), folds=masks, K1=p.left.K, D1=p.left.D, K2=p.right.K, D2=p.right.D,
             R=np.asarray(p.R, float), T=np.asarray(p.T, float).reshape(3))
    proc = subprocess.run([python, str(MRCAL_SCRIPT), str(inp), str(out)], capture_output=True, text=True,
                          check=False)
    if proc.returncode != 0:
        return {"error": proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else "mrcal failed"}
    d = np.load(out)
    result: dict[str, Any] = {}
    for variant in ("flat", "warp"):
        models = []
        for intr, rt, board in zip(d[f"{variant}_intrinsics"], d[f"{variant}_rt"], d[f"{variant}_board"],
                                   strict=True):
            ks = [np.array([[c[0], 0, c[2]], [0, c[1], c[3]], [0, 0, 1]]) for c in intr]
            rm, _ = cv2.Rodrigues(rt[:3])
            models.append(Model(ks[0], intr[0, 4:], ks[1], intr[1, 4:], rm, rt[3:], board))
        result[f"heldout_{variant}"] = fold_heldout(models, left, right)
        result[f"jackknife_{variant}"] = jackknife([m.params9() for m in models]).tolist()
        result[f"rms_{variant}"] = float(d[f"{variant}_full_rms"])
        result[f"warp_mm_{variant}"] = [float(v) * 1000 for v in d[f"{variant}_full_warp"]]
    return result


def _copy(src: Path, dst: Path, noise: float, rng: np.random.Generator) -> None:
    """``dst`` links to ``src``, or (``noise`` > 0) is ``src`` with Gaussian noise of that std (grey levels)
    as lossless PNG: a still board recorded again, as in a bag."""
    if noise <= 0:
        dst.with_suffix(src.suffix).symlink_to(src.resolve())
        return
    img = cv2.imread(str(src), cv2.IMREAD_UNCHANGED).astype(np.float64)
    cv2.imwrite(str(dst.with_suffix(".png")), np.clip(img + rng.normal(0, noise, img.shape), 0, 255).astype(np.uint8))


def repeat_check(pairs: Any, spec: SetSpec, cache: Path, folder: Path, unique: dict[str, float], *,
                 noise: float = 0.0) -> dict[str, Any]:
    """s2r on the set with every pair 3 times (links, or the copies with ``noise``): its reported std over
    the unique-view one."""
    rng = np.random.default_rng(0)
    for side in ("left", "right"):
        (folder / side).mkdir(parents=True)
    k = 0
    for lp, rp in zip(pairs.left, pairs.right, strict=True):
        for copy in range(3):
            for src, side in ((Path(lp), "left"), (Path(rp), "right")):
                _copy(src, folder / side / f"{k:04d}", noise if copy else 0.0, rng)
            k += 1
    rp_ = find_stereo_pairs(folder)
    try:
        res = run_s2r(rp_.left, rp_.right, rp_.names, spec, cache)
    except Exception as exc:  # s2r's own errors, and any crash: reported, the run goes on
        return {"error": _why(exc)}
    stds = _reported(res)
    ratios = {n: stds[n] / unique[n] for n in NAMES9 if stds.get(n) and unique.get(n)}
    return {"ratios": ratios, "within_15pct": sum(abs(r - 1) <= 0.15 for r in ratios.values()),
            "used": len(res.used_names), "warnings": [w for w in res.warnings if "repeat" in w]}


def _reported(res: StereoCalibration) -> dict[str, float]:
    h = res.figures()["stereo_heldout"] or {}
    return {n: v["std"] for n, v in h.get("parameters", {}).items() if v.get("std") is not None}


def bench_set(spec: SetSpec, *, mrcal_python: str, repeat: bool) -> dict[str, Any]:
    """Every figure of one set (see the module docstring)."""
    pairs = find_stereo_pairs(spec.folder)
    board = board_points(spec.pattern, spec.square)
    t0 = time.perf_counter()
    det = [(plain_detect(lp, spec.pattern), plain_detect(rp, spec.pattern)) for lp, rp in
           zip(pairs.left, pairs.right, strict=True)]
    size = det[0][0][1]
    plain = [(a[0], b[0]) for a, b in det]
    both = [(a, b) for a, b in plain if a is not None and b is not None]
    pl, pr = [a for a, _ in both], [b for _, b in both]
    plain_full = opencv_model(pl, pr, board, size)
    plain_jk = jackknife([opencv_model([pl[i] for i in range(len(pl)) if i not in set(f)],
                                       [pr[i] for i in range(len(pr)) if i not in set(f)], board, size).params9()
                          for f in folds_of(len(pl))])
    t_plain = time.perf_counter() - t0
    plain_own = fold_heldout([opencv_model([pl[i] for i in range(len(pl)) if i not in set(f)],
                                           [pr[i] for i in range(len(pr)) if i not in set(f)], board, size)
                              for f in folds_of(len(pl))], pl, pr)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        cache = tmp / "cache"
        t0 = time.perf_counter()
        try:
            res = run_s2r(pairs.left, pairs.right, pairs.names, spec, cache)
        except Exception as exc:  # the plain figures are still worth printing
            return {"set": spec.name, "error": _why(exc), "pairs": len(pairs.names), "size": list(size),
                    "plain_boards": sum((a is not None) + (b is not None) for a, b in plain),
                    "plain_jackknife": dict(zip(NAMES9, plain_jk.tolist(), strict=True)),
                    "plain_values": dict(zip(NAMES9, plain_full.params9().tolist(), strict=True)),
                    "plain_own_px": plain_own}
        t_s2r = time.perf_counter() - t0
        fig = res.figures()
        h = fig["stereo_heldout"] or {}
        left = [np.asarray(c, np.float64).reshape(-1, 2) for c in res.corners_left]
        right = [np.asarray(c, np.float64).reshape(-1, 2) for c in res.corners_right]
        flat, warped, notes = s2r_fold_models(pairs, res, spec, cache, board)
        cv_models = [opencv_model([left[i] for i in range(len(left)) if i not in set(f)],
                                  [right[i] for i in range(len(right)) if i not in set(f)], board, size)
                     for f in folds_of(len(left))]
        s2r_full = s2r_model(res, board)
        sq_flat, sq_warp = fold_sq(flat, left, right), fold_sq(warped, left, right)
        params = h.get("parameters", {})
        mrcal = run_mrcal(mrcal_python, res, left, right, spec, size, tmp)
        mrcal_jk = mrcal.get("jackknife_warp", [None] * len(NAMES9))
        cv_jk = jackknife([m.params9() for m in cv_models])
        sigma = {n: {"value": float(s2r_full.params9()[i]), "plain_value": float(plain_full.params9()[i]),
                     "reported": params.get(n, {}).get("std"), "covariance": params.get(n, {}).get("std_covariance"),
                     "s2r_jackknife": params.get(n, {}).get("std_jackknife"), "plain_jackknife": float(plain_jk[i]),
                     "mrcal_jackknife": mrcal_jk[i], "opencv_s2r_corners_jackknife": float(cv_jk[i])}
                 for i, n in enumerate(NAMES9)}
        out: dict[str, Any] = {
            "set": spec.name, "folder": str(spec.folder), "pattern": list(spec.pattern), "square_m": spec.square,
            "pairs": len(pairs.names), "size": list(size), "used": len(res.used_names),
            "time_s2r_s": t_s2r, "time_plain_s": t_plain, "verdict": (fig["verdict"] or {}).get("level"),
            "boards": board_check(pairs, plain, res), "dropped": [(d.name, d.reason) for d in res.dropped],
            "sigma": sigma, "board_warp": fig["board_warp"], "fold_notes": notes,
            "json_heldout_px": h.get("heldout_px"), "json_heldout_all_px": h.get("heldout_all_px"),
            "json_corners_rejected": h.get("corners_rejected"), "json_corners_total": h.get("corners_total"),
            "script_s2r_flat_px": None if sq_flat is None else rms([sq_flat]),
            "script_s2r_warp_px": None if sq_warp is None else rms([sq_warp]),
            "script_s2r_flat_trimmed": trimmed(sq_flat), "script_s2r_warp_trimmed": trimmed(sq_warp),
            "script_opencv_px": fold_heldout(cv_models, left, right), "plain_own_px": plain_own,
            "mrcal": mrcal,
        }
        if repeat:
            out["repeat"] = repeat_check(pairs, spec, cache, tmp / "repeat", _reported(res))
            out["repeat_noisy"] = repeat_check(pairs, spec, cache, tmp / "repeat_noisy", _reported(res),
                                               noise=REPEAT_NOISE)
    return out


def _ratio(a: float | None, b: float | None) -> float | None:
    return None if a is None or b is None or not b else a / b


def _f(v: float | None, fmt: str = ".4f") -> str:
    return "-" if v is None else format(v, fmt)


def report(r: dict[str, Any]) -> list[str]:
    """The set's lines (markdown)."""
    b = r["boards"]
    lines = [f"## {r['set']}: {r['pairs']} pairs {r['size'][0]}x{r['size'][1]}, board {r['pattern'][0]}x"
             f"{r['pattern'][1]} at {r['square_m'] * 1000:g} mm; s2r used {r['used']}, verdict {r['verdict']}; "
             f"s2r {r['time_s2r_s']:.1f} s, plain {r['time_plain_s']:.1f} s",
             f"- boards: plain finds {b['plain_boards']} of {b['images']} images; lost by s2r (not used, not "
             f"listed): {len(b['lost'])} {b['lost']}; dropped with a reason: {b['listed']}",
             "", "| parameter | s2r | plain | reported σ | s2r jackknife | plain jackknife | mrcal jackknife | "
             "σ/plain jk | σ/mrcal jk | σ/s2r jk |", "|---|---|---|---|---|---|---|---|---|---|"]
    ok_plain = ok_s2r = ok_mrcal = ok_cv = 0
    for n, s in r["sigma"].items():
        scale = 1000.0 if n == "baseline" else 1.0
        rp, rs = _ratio(s["reported"], s["plain_jackknife"]), _ratio(s["reported"], s["s2r_jackknife"])
        rm = _ratio(s["reported"], s["mrcal_jackknife"])
        ok_plain += rp is not None and 0.5 <= rp <= 3
        ok_s2r += rs is not None and 0.5 <= rs <= 3
        ok_mrcal += rm is not None and 0.5 <= rm <= 3
        rc = _ratio(s["reported"], s["opencv_s2r_corners_jackknife"])
        ok_cv += rc is not None and 0.5 <= rc <= 3
        sc = [None if v is None else v * scale for v in (s["value"], s["plain_value"], s["reported"],
                                                           s["s2r_jackknife"], s["plain_jackknife"],
                                                           s["mrcal_jackknife"])]
        lines.append(f"| {n}{' (mm)' if scale != 1 else ''} | {_f(sc[0], '.3f')} | {_f(sc[1], '.3f')} | "
                     f"{_f(sc[2])} | {_f(sc[3])} | {_f(sc[4])} | {_f(sc[5])} | {_f(rp, '.2f')} | {_f(rm, '.2f')} | "
                     f"{_f(rs, '.2f')} |")
    lines.append(f"- σ ratio in [0.5, 3]: {ok_plain}/9 against plain OpenCV's jackknife, {ok_mrcal}/9 against "
                 f"mrcal's (warp, on s2r's corners), {ok_cv}/9 against OpenCV's on s2r's corners, "
                 f"{ok_s2r}/9 against s2r's")
    m = r["mrcal"]
    js, sc = r["json_heldout_px"], r["script_s2r_flat_px"]
    sw = r["script_s2r_warp_px"]
    mw, mf = m.get("heldout_warp"), m.get("heldout_flat")
    lines.append(f"- held-out (px): --json {_f(js)} (all corners {_f(r['json_heldout_all_px'])}, "
                 f"{r['json_corners_rejected']}/{r['json_corners_total']} rejected); this script: s2r profile "
                 f"{_f(sc)} (with its warp {_f(sw)}), OpenCV on s2r's corners {_f(r['script_opencv_px'])}, "
                 f"mrcal flat {_f(mf)}, mrcal warp {_f(mw)} {m.get('error', '')}")
    (tf, nf), (tw, nw) = r["script_s2r_flat_trimmed"], r["script_s2r_warp_trimmed"]
    lines.append(f"- this script trimmed (median + 5 robust σ): s2r profile {_f(tf)} ({nf} corners out), with its "
                 f"warp {_f(tw)} ({nw} out); --json inlier / trimmed: {_f(_ratio(js, tw if sw != sc else tf), '.3f')}")
    best = min((v for v in (sc, sw) if v is not None), default=None)
    lines.append(f"- --json all corners / script: {_f(_ratio(r['json_heldout_all_px'], sw), '.3f')} (s2r's model with "
                 f"its warp), {_f(_ratio(r['json_heldout_all_px'], sc), '.3f')} (the flat profile); --json inlier / "
                 f"script all corners {_f(_ratio(js, sw), '.3f')}; s2r / mrcal warp: {_f(_ratio(best, mw), '.3f')}; "
                 f"s2r / OpenCV: {_f(_ratio(best, r['script_opencv_px']), '.3f')}; plain OpenCV on its own corners "
                 f"and pairs: {_f(r['plain_own_px'])}")
    if r["board_warp"]:
        lines.append(f"- s2r board warp: {r['board_warp']}; mrcal's {m.get('warp_mm_warp')}")
    for key, label in (("repeat", "linked"), ("repeat_noisy", f"noisy copies, {REPEAT_NOISE:g} grey levels")):
        rep = r.get(key)
        if rep:
            ratios = {k: round(v, 3) for k, v in rep.get("ratios", {}).items()}
            lines.append(f"- repeated x3 ({label}): {rep.get('error') or ''} used {rep.get('used')}, "
                         f"σ(repeat)/σ(unique) {ratios}; within 15 %: {rep.get('within_15pct')}/{len(ratios)}; "
                         f"warnings {rep.get('warnings')}")
    if r["fold_notes"]:
        lines.append(f"- fold notes: {r['fold_notes']}")
    return lines


def _why(exc: BaseException) -> str:
    lines = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {' / '.join(x.strip() for x in lines[:2])}"


def _share(r: dict[str, Any], key: str) -> int:
    return sum(1 for s in r["sigma"].values()
               if (q := _ratio(s["reported"], s[key])) is not None and 0.5 <= q <= 3)


def summary(results: Sequence[dict[str, Any]]) -> list[str]:
    """One markdown row per set with the bars' figures."""
    lines = ["| set | pairs | size | plain boards / lost | σ/plain jk in [0.5,3] | σ/mrcal jk | "
             "σ/OpenCV jk (s2r corners) | σ/s2r jk | "
             "--json all / script | s2r / mrcal warp | s2r / OpenCV | repeat σ within 15 % (linked, noisy) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        if "error" in r:
            lines.append(f"| {r['set']} | s2r failed: {r['error']} |")
            continue
        sw, mw = r["script_s2r_warp_px"], r["mrcal"].get("heldout_warp")
        best = min((v for v in (r["script_s2r_flat_px"], sw) if v is not None), default=None)
        reps = [r.get(k, {}) for k in ("repeat", "repeat_noisy")]
        rep = ", ".join("-" if not x else f"{x.get('within_15pct')}/{len(x.get('ratios', {}))}" for x in reps)
        lines.append(
            f"| {r['set']} | {r['pairs']} | {r['size'][0]}x{r['size'][1]} | {r['boards']['plain_boards']} / "
            f"{len(r['boards']['lost'])} | {_share(r, 'plain_jackknife')}/9 | {_share(r, 'mrcal_jackknife')}/9 | "
            f"{_share(r, 'opencv_s2r_corners_jackknife')}/9 | "
            f"{_share(r, 's2r_jackknife')}/9 | "
            f"{_f(_ratio(r['json_heldout_all_px'], sw), '.3f')} | {_f(_ratio(best, mw), '.3f')} | "
            f"{_f(_ratio(best, r['script_opencv_px']), '.3f')} | {rep} |")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    ap.add_argument("sets", nargs="+", help="NAME=FOLDER:COLSxROWS:SQUARE_M")
    ap.add_argument("--mrcal-python", default="/usr/bin/python3", help="a python with mrcal (Debian's)")
    ap.add_argument("--repeat", action="store_true",
                    help="also run every set with each pair 3 times (linked, then as noisy copies)")
    ap.add_argument("--json", type=Path, help="write every figure here too")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    results = []
    for spec in (parse_spec(s) for s in args.sets):
        try:
            r = bench_set(spec, mrcal_python=args.mrcal_python, repeat=args.repeat)
        except Exception as exc:  # s2r's own errors, and any crash: reported, the run goes on
            r = {"set": spec.name, "error": _why(exc)}
        results.append(r)
        if "error" in r:
            print(f"## {spec.name}: s2r failed: {r['error']}\n{ {k: v for k, v in r.items() if k != 'error'} }\n",
                  flush=True)
            continue
        print("\n".join(report(r)) + "\n", flush=True)
    print("\n".join(summary(results)))
    if args.json:
        args.json.write_text(json.dumps(results, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Root causes: the failing checks of a validation grouped by the one sim parameter that explains them.

One wrong ``<horizontal_fov>`` fails fx, fy, HFOV, VFOV, the projection shift, the 2 % depth distance and
the depth-accuracy gaps: a flat list of 17 failures hides the single edit that fixes them. Every failing
check is attributed to exactly one root cause, in this order:

``resolution``      image size (fx, fy, cx, cy follow it when the field of view and centre match);
``focal``           focal length / field of view (HFOV, VFOV; fx, fy);
``principal_point`` the principal point off the image centre (cx, cy);
``lens``            distortion model or coefficients;
``baseline``        the distance between the cameras;
``rotation``        the rotation between the cameras;
``depth``           depth accuracy or fill rate that no parameter explains (the matcher, the renderer);
``projection``      a projection shift beyond tolerance though no single parameter is;
``bench``           the renderer/calibrator self-test (the test bench itself, not the sim-vs-real answer).

Consequences that depend on ``fx * B`` (the 2 % depth distance, depth gaps) go to whichever of focal length
and baseline changes ``fx * B`` more (by ``|log(sim / real)|``); projection shifts go to the first failing
intrinsic cause (focal, principal point, lens, resolution), else to the extrinsic ones for the right camera.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from s2r.profile import StereoProfile
from s2r.validate.advice.edits import Edit
from s2r.validate.measures.params import ParamRow
from s2r.validate.verdict import Check

__all__ = ["CAUSE_TITLES", "RootCause", "group_failures"]

#: Root-cause keys in reading order, with their titles.
CAUSE_TITLES: dict[str, str] = {
    "resolution": "Resolution",
    "focal": "Focal length / field of view",
    "principal_point": "Principal point",
    "lens": "Lens distortion",
    "baseline": "Baseline",
    "rotation": "Rotation between the cameras",
    "depth": "Depth accuracy",
    "projection": "Projection",
    "bench": "The test bench itself",
}

#: Which parameter rows are the cause itself (the first failing one is quoted as "what differs").
_OWN_PARAMS: dict[str, tuple[str, ...]] = {
    "resolution": ("image size",),
    "focal": ("HFOV", "VFOV", "left fx", "left fy", "right fx", "right fy"),
    "principal_point": ("left cx", "left cy", "right cx", "right cy"),
    "lens": ("left distortion", "right distortion"),
    "baseline": ("baseline",),
    "rotation": ("inter-camera rotation",),
}
#: The edit (``Edit.parameter`` from :func:`s2r.validate.advice.edits.suggest_edits`) that removes each cause.
#: A MuJoCo sim's edits (:func:`s2r.validate.advice.mujoco.suggest_mujoco_edits`) are listed beside Gazebo's.
_EDIT_FOR: dict[str, tuple[str, ...]] = {
    "resolution": ("resolution",),
    "focal": ("horizontal_fov", "fy", "fovy", "intrinsics"),
    "principal_point": ("principal point", "intrinsics"),
    "lens": ("distortion",),
    "baseline": ("right camera joint origin", "right camera pos"),
    "rotation": ("right camera joint origin", "right camera pos"),
    "projection": ("sensor XML", "MJCF cameras"),
}


@dataclass
class RootCause:
    """One reason the sim differs: what differs, the failing checks it explains and the one edit that fixes it.

    ``checks`` are the failing checks attributed to this cause (its own parameters first, then consequences);
    ``edits`` the edit(s) to the sim description (usually one; empty for ``depth`` and ``bench``, whose
    ``fix`` text says what to do).
    """

    key: str
    what: str
    fix: str
    checks: list[Check] = field(default_factory=list)
    edits: list[Edit] = field(default_factory=list)
    primary: str = ""  # name of the check quoted in ``what`` (not repeated among the consequences)

    @property
    def title(self) -> str:
        """Human title of the cause (``Focal length / field of view``)."""
        return CAUSE_TITLES[self.key]

    @property
    def short_fix(self) -> str:
        """The fix without the where-to-write-it detail (one terminal line for most causes)."""
        if not self.edits or self.fix.startswith("the same edit"):
            return self.fix
        return "; ".join(f"{e.parameter} {e.current} -> {e.target}" for e in self.edits)

    @property
    def consequences(self) -> list[Check]:
        """Every attributed failing check but the one quoted in ``what``: what else this one cause breaks."""
        return [c for c in self.checks if c.name != self.primary]

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON (``root_causes`` in ``s2r validate --json``)."""
        return {"cause": self.key, "title": self.title, "what": self.what, "fix": self.fix,
                "edits": [e.as_dict() for e in self.edits], "checks": [c.name for c in self.checks],
                "consequences": [c.text for c in self.consequences]}


def _failed_rows(rows: Sequence[ParamRow]) -> dict[str, ParamRow]:
    return {r.name: r for r in rows if r.exceeds_tolerance}


def _what(rows: Sequence[ParamRow], names: Sequence[str]) -> tuple[str, str]:
    """``("HFOV", "HFOV: sim 60 vs real 86.9 deg")`` for the first row among ``names`` (failing ones first)."""
    by_name = {r.name: r for r in rows}
    ordered = [n for n in names if n in by_name and by_name[n].exceeds_tolerance] + list(names)
    for name in ordered:
        r = by_name.get(name)
        if r is not None:
            sim = r.sim if isinstance(r.sim, str) else f"{r.sim:.4g}"
            real = r.real if isinstance(r.real, str) else f"{r.real:.4g}"
            unit = "" if r.unit.startswith("max") or (r.unit == "px" and "x" in sim) else f" {r.unit}"
            return r.name, f"{r.name}: sim {sim} vs real {real}{unit}"
    return "", ""


def _centre_offsets(sim: StereoProfile, real: StereoProfile) -> str:
    """Where each left principal point sits from its image centre ((W - 1) / 2, (H - 1) / 2), pixels."""
    def offset(p: StereoProfile) -> str:
        cam = p.left
        return f"({cam.cx_px - (cam.width_px - 1) / 2:+.2f}, {cam.cy_px - (cam.height_px - 1) / 2:+.2f})"

    return f"left principal point from the image centre: sim {offset(sim)} px vs real {offset(real)} px"


def _own_causes(failed: dict[str, ParamRow], pp_edit: bool) -> dict[str, list[str]]:
    """Parameter rows attributed to each parameter cause (``{cause: [row names]}``)."""
    causes: dict[str, list[str]] = {}
    size = "image size" in failed
    # Gazebo ties fy to fx: with another aspect ratio the VFOV follows the resolution, the HFOV does not
    fov = "HFOV" in failed or ("VFOV" in failed and not size)
    for name in failed:
        if name == "image size":
            key = "resolution"
        elif name in _OWN_PARAMS["focal"]:
            key = "focal" if fov or not size else "resolution"
        elif name in _OWN_PARAMS["principal_point"]:
            key = "principal_point" if pp_edit or not size else "resolution"
        elif name in _OWN_PARAMS["lens"]:
            key = "lens"
        elif name == "baseline":
            key = "baseline"
        elif name == "inter-camera rotation":
            key = "rotation"
        else:
            continue  # consequences (the 2 % depth distance) are placed later
        causes.setdefault(key, []).append(name)
    return causes


def _fb_cause(causes: dict[str, list[str]], sim: StereoProfile | None, real: StereoProfile | None) -> str:
    """The cause that changes ``fx * B`` most (``focal`` or ``baseline``); else ``lens`` when the lenses differ
    (rectifying a distorted image rescales it, which changes the rectified focal length, the matcher's range and
    the fill rate); else ``depth``."""
    candidates = [k for k in ("focal", "baseline", "resolution") if k in causes]
    if not candidates and "lens" in causes:
        return "lens"
    if not candidates or sim is None or real is None:
        return "depth"
    weight = {"focal": abs(math.log(sim.left.fx_px / real.left.fx_px)),
              "baseline": abs(math.log(sim.baseline_m / real.baseline_m)),
              "resolution": abs(math.log(sim.left.fx_px / real.left.fx_px))}
    return max(candidates, key=lambda k: weight[k])


def _projection_cause(check: Check, causes: dict[str, list[str]]) -> str:
    order = ["focal", "principal_point", "lens", "resolution"]
    if check.name.startswith("right"):
        order += ["baseline", "rotation"]
    return next((k for k in order if k in causes), "projection")


def _attribute(check: Check, causes: dict[str, list[str]], fb_key: str) -> str:
    """The root-cause key of one failing check."""
    if check.section == "recovery":
        return "bench"
    if check.section == "projection":
        return _projection_cause(check, causes)
    if check.section == "depth gap" or check.name == "2% depth distance":
        return fb_key
    if check.section == "parameters":
        return next((k for k, names in causes.items() if check.name in names), "depth")
    return "depth"


def _fix_text(key: str, edits: Sequence[Edit], preset: str, *, mujoco: bool = False) -> str:
    if edits:
        return "; ".join(f"{e.parameter}: {e.current} -> {e.target} [{e.where}]" for e in edits)
    if key == "bench":
        return ("nothing in the sim: the renderer + calibration chain did not recover a profile it rendered, so "
                "the figures above carry that extra error (rerun without --quick, or report it)")
    if key == "depth":
        return (f"the matcher, not the camera: try another --preset than {preset!r} or tune the profile's "
                "matcher settings (num_disparities, block size) and validate again")
    if mujoco:
        return "s2r profile export-mujoco REAL writes the real camera's MJCF camera pair"
    return "s2r profile export-gazebo REAL writes the real camera's sensor XML"


def group_failures(checks: Sequence[Check], rows: Sequence[ParamRow], edits: Sequence[Edit], *,
                   sim: StereoProfile | None = None, real: StereoProfile | None = None,
                   preset: str = "profile") -> list[RootCause]:
    """The failing ``checks`` grouped by root cause, in :data:`CAUSE_TITLES` order; [] when all pass.

    ``rows`` and ``edits`` are the validation's parameter table and suggested edits; ``sim``/``real`` the
    profiles compared (OpenCV pixels), used to weigh focal length against baseline for ``fx * B`` effects.
    """
    failed = _failed_rows(rows)
    pp_edit = any(e.parameter in ("principal point", "intrinsics") for e in edits)
    causes = _own_causes(failed, pp_edit)
    fb_key = _fb_cause(causes, sim, real)
    grouped: dict[str, list[Check]] = {}
    for check in checks:
        if not check.passed:
            grouped.setdefault(_attribute(check, causes, fb_key), []).append(check)
    out: list[RootCause] = []
    for key in (k for k in CAUSE_TITLES if k in grouped):
        mine = [e for e in edits if e.parameter in _EDIT_FOR.get(key, ())]
        primary, what = (_what(rows, _OWN_PARAMS[key]) if key in _OWN_PARAMS
                         else (grouped[key][0].name, grouped[key][0].text))
        if key == "principal_point" and sim is not None and real is not None:
            primary, what = "", _centre_offsets(sim, real)
        earlier = next((c for c in out if mine and c.edits == mine), None)
        fix = (f"the same edit as {earlier.title.lower()} ({', '.join(e.parameter for e in mine)})"
               if earlier is not None else _fix_text(key, mine, preset,
                                                     mujoco=any(e.parameter == "MJCF cameras" for e in edits)))
        out.append(RootCause(key, what, fix, grouped[key], mine, primary))
    return out

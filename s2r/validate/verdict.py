"""The verdict: every figure compared with its tolerance, as a flat list of named checks.

Exit code of ``s2r validate``: 0 when every check passes, 1 when any fails (the failing checks are listed).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

from s2r.validate.measures.depth_accuracy import BinStats, DepthAccuracy
from s2r.validate.measures.params import ParamRow
from s2r.validate.measures.projection import ProjectionDiff
from s2r.validate.measures.recovery import RecoveryResult
from s2r.validate.tolerances import Tolerances

__all__ = ["Check", "depth_checks", "depth_gap_checks", "parameter_checks", "projection_checks", "recovery_checks"]


@dataclass(frozen=True)
class Check:
    """One pass/fail figure: ``value`` against ``limit`` (same ``unit``), with a one-line ``text``."""

    section: str
    name: str
    value: float | str
    limit: float | str
    unit: str
    passed: bool
    text: str

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return asdict(self)


def _num(value: float | str) -> str:
    return value if isinstance(value, str) else f"{value:.4g}"


def parameter_checks(rows: Sequence[ParamRow]) -> list[Check]:
    """One check per parameter row: ``|sim - real|`` within the row's limit."""
    out = []
    for r in rows:
        text = f"{r.name}: sim {_num(r.sim)} vs real {_num(r.real)} {r.unit} (diff {r.diff:+.4g}, limit {r.limit:.4g})"
        out.append(Check("parameters", r.name, r.diff, r.limit, r.unit, not r.exceeds_tolerance, text))
    return out


def projection_checks(diffs: Sequence[ProjectionDiff], tol: Tolerances) -> list[Check]:
    """The 95th-percentile projection shift of each camera within ``projection_p95_px``."""
    return [Check("projection", f"{d.camera} projection p95", d.p95_px, tol.projection_p95_px, "px",
                  d.p95_px <= tol.projection_p95_px,
                  f"{d.camera} camera projection shift at {d.distance_m:g} m: mean {d.mean_px:.3g} px, "
                  f"p95 {d.p95_px:.3g} px (limit {tol.projection_p95_px:g})") for d in diffs]


def recovery_checks(result: RecoveryResult, label: str) -> list[Check]:
    """Each recovered parameter within its predicted sigmas or floor."""
    out = []
    for r in result.rows:
        sig = f", {r.n_sigma:.2g} sigma" if r.n_sigma is not None else ""
        text = (f"{label} recovered {r.name}: {r.recovered:.5g} vs declared {r.declared:.5g} {r.unit} "
                f"(error {r.error:+.3g}{sig}, floor {r.floor:.3g})")
        out.append(Check("recovery", f"{label} {r.name}", r.error, r.floor, r.unit, r.passed, text))
    return out


def _bin_name(b: BinStats) -> str:
    return f"{b.lo_m:g}-{b.hi_m:g} m"


def depth_checks(acc: DepthAccuracy, tol: Tolerances, label: str) -> list[Check]:
    """Per bin with pixels: median error under the theory bound and fill rate above ``min_fill``."""
    out = []
    for b in acc.bins:
        if not b.pixels:
            continue
        name = _bin_name(b)
        theory = b.theory_hi_pct or 0.0
        limit = tol.depth_theory_factor * theory + tol.depth_floor_pct
        med = b.median_pct
        ok = med is not None and med <= limit
        out.append(Check("depth", f"{label} median error {name}", "none" if med is None else med, limit, "%", ok,
                         f"{label} {name}: median |error| {_num(med) if med is not None else 'n/a'} % (limit "
                         f"{limit:.3g} % = {tol.depth_theory_factor:g} x theory {theory:.3g} % + "
                         f"{tol.depth_floor_pct:g})"))
        fill = b.fill_rate or 0.0
        out.append(Check("depth", f"{label} fill rate {name}", fill, tol.min_fill, "", fill >= tol.min_fill,
                         f"{label} {name}: fill rate {fill:.0%} (minimum {tol.min_fill:.0%})"))
    return out


def depth_gap_checks(sim: DepthAccuracy, real: DepthAccuracy, tol: Tolerances) -> list[Check]:
    """Sim-to-real gap per bin: difference in median error and in fill rate."""
    out = []
    for bs, br in zip(sim.bins, real.bins, strict=True):
        if not bs.pixels or not br.pixels:
            continue
        name = _bin_name(bs)
        if bs.median_pct is not None and br.median_pct is not None:
            gap = bs.median_pct - br.median_pct
            out.append(Check("depth gap", f"median error gap {name}", gap, tol.depth_gap_pct, "% points",
                             abs(gap) <= tol.depth_gap_pct,
                             f"depth {name}: median |error| sim {bs.median_pct:.3g} % vs real {br.median_pct:.3g} % "
                             f"(gap {gap:+.3g}, limit {tol.depth_gap_pct:g} points)"))
        fill_gap = (bs.fill_rate or 0.0) - (br.fill_rate or 0.0)
        ok = abs(fill_gap) <= tol.fill_gap
        out.append(Check("depth gap", f"fill rate gap {name}", fill_gap, tol.fill_gap, "", ok,
                         f"depth {name}: fill rate sim {bs.fill_rate or 0:.0%} vs real {br.fill_rate or 0:.0%} "
                         f"(limit {tol.fill_gap:.0%})"))
    return out

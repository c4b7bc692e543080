"""What a fleet run keeps between runs: the journal of finished robots (``--resume``) and the history (``--history``).

Journal: ``OUT/.s2r-fleet-journal/NAME.json``, one file per finished robot, written atomically as its result
arrives, with the key of the job that produced it (profile, recording, settings): ``--resume`` reuses a robot's
result only when its key is the same, so a changed fleet file re-checks what changed. The journal goes when the
run's outputs are published (they are published whole, by one OutputBatch, or not at all).

History: ``HISTORY/run-YYYYmmddTHHMMSSZ-XXXXXXXX.json``, one file per finished run: its UTC time and, per robot,
the verdict, the rotation error and sigma (deg, about the right camera's optical axes), the tolerance and the
recording's identity (where it was read, the number of pairs and a SHA-256 of their pixels). :func:`robot_trends`
reads the most recent :data:`MAX_HISTORY_RUNS` of them back as one series per robot, oldest first.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import hashlib
import json
import logging
import math
import secrets
import shutil
from pathlib import Path
from typing import Any

from s2r.drift.check import AXES
from s2r.errors import CheckError, S2RError
from s2r.fileio import MAX_TEXT_BYTES, atomic_write_text, read_regular_file

__all__ = ["JOURNAL", "MAX_HISTORY_RUNS", "Journal", "check_history_folder", "history_entry", "job_key", "robot_trends",
           "trend_summary", "write_history"]

log = logging.getLogger(__name__)

#: The journal's folder inside the output folder.
JOURNAL = ".s2r-fleet-journal"
#: Runs of the history read back for the trends (the most recent ones).
MAX_HISTORY_RUNS = 60
_RUN_PREFIX = "run-"


def _json(data: Any) -> str:
    """JSON of plain data with numpy scalars as numbers (NaN kept: Python's json reads it back)."""
    return json.dumps(data, default=lambda v: v.item() if hasattr(v, "item") else str(v))


def job_key(job: Any) -> str:
    """A digest of everything that decides a robot's result: name, profile, recording and settings."""
    return hashlib.sha256(repr(job).encode("utf-8")).hexdigest()[:32]


def _read_json(path: Path) -> Any:
    """The JSON document at ``path`` (bounded read of a regular file); None when it is unreadable or torn."""
    try:
        return json.loads(read_regular_file(path, limit=MAX_TEXT_BYTES, follow_links=False).decode("utf-8"))
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        log.warning("%s: skipped (%s)", path, exc)
        return None


class Journal:
    """The finished robots of a run in ``out`` (see the module docstring)."""

    def __init__(self, out: Path) -> None:
        self.out = out
        self.folder = out / JOURNAL

    def exists(self) -> bool:
        return self.folder.is_dir() and not self.folder.is_symlink()

    def finished(self, keys: dict[str, str]) -> dict[str, dict[str, Any]]:
        """The journalled rows of the robots named in ``keys`` (name -> job key) whose key still matches."""
        rows: dict[str, dict[str, Any]] = {}
        if not self.exists():
            return rows
        for name, key in keys.items():
            path = self.folder / f"{name}.json"
            data = _read_json(path) if path.is_file() else None
            if isinstance(data, dict) and data.get("key") == key and isinstance(data.get("row"), dict):
                rows[name] = data["row"]
        return rows

    def add(self, row: dict[str, Any], key: str) -> None:
        """Persist one robot's finished row, atomically (a crash leaves the old file or none)."""
        atomic_write_text(self.folder / f"{row['name']}.json", _json({"key": key, "row": row}), force=True,
                          root=self.out)

    def remove(self) -> None:
        """Drop the journal (after the outputs were published)."""
        if self.exists():
            shutil.rmtree(self.folder, ignore_errors=True)


def _recording_identity(row: dict[str, Any]) -> dict[str, Any]:
    return dict(row.get("recording") or {})


def history_entry(rows: list[dict[str, Any]], *, when: dt.datetime) -> dict[str, Any]:
    """One run's record for the history: its UTC time and each robot's verdict, rotation and recording."""
    keep = ("verdict", "rotation_error_deg", "sigma_deg", "tolerance_deg", "matches")
    return {"schema": 1, "time": when.astimezone(dt.timezone.utc).isoformat(timespec="seconds"),
            "robots": {r["name"]: {**{k: r.get(k) for k in keep}, "recording": _recording_identity(r)}
                       for r in rows}}


def write_history(folder: Path, entry: dict[str, Any]) -> Path:
    """Add ``entry`` to the history folder as a new file (never replacing one); its path."""
    if folder.is_symlink() or (folder.exists() and not folder.is_dir()):
        raise CheckError("is not a folder", path=folder, field="--history", hint="give a history folder")
    stamp = dt.datetime.fromisoformat(entry["time"]).strftime("%Y%m%dT%H%M%SZ")
    path = folder / f"{_RUN_PREFIX}{stamp}-{secrets.token_hex(4)}.json"
    return atomic_write_text(path, _json(entry), root=folder)


def _runs(folder: Path) -> list[dict[str, Any]]:
    """The history's most recent runs (by file name, which starts with the UTC time), oldest first."""
    if not folder.is_dir():
        return []
    names = sorted(p.name for p in folder.iterdir() if p.name.startswith(_RUN_PREFIX) and p.suffix == ".json")
    runs = [_read_json(folder / name) for name in names[-MAX_HISTORY_RUNS:]]
    return [r for r in runs if isinstance(r, dict) and isinstance(r.get("robots"), dict) and "time" in r]


def _point(when: str, robot: dict[str, Any]) -> dict[str, Any]:
    error = robot.get("rotation_error_deg") or {}
    sigma = robot.get("sigma_deg") or {}
    return {"time": when, "verdict": robot.get("verdict"),
            "rotation_error_deg": {a: _number(error.get(a)) for a in AXES},
            "sigma_deg": {a: _number(sigma.get(a)) for a in AXES},
            "tolerance_deg": {a: _number((robot.get("tolerance_deg") or {}).get(a)) for a in AXES},
            "recording": robot.get("recording") or {}}


def _number(value: Any) -> float | None:
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) else None


def robot_trends(folder: Path | None, current: dict[str, Any] | None = None) -> dict[str, list[dict[str, Any]]]:
    """Per robot, its points over the history's runs and then ``current`` (a :func:`history_entry`), oldest
    first; each point has ``time``, ``verdict``, ``rotation_error_deg`` / ``sigma_deg`` per axis (None when not
    estimated) and ``recording``."""
    runs = _runs(folder) if folder is not None else []
    trends: dict[str, list[dict[str, Any]]] = {}
    for run in [*runs, *([current] if current else [])]:
        for name, robot in run["robots"].items():
            if isinstance(robot, dict):
                trends.setdefault(str(name), []).append(_point(str(run["time"]), robot))
    return trends


def check_history_folder(folder: Path) -> Path:
    """``folder`` usable as the history (a real folder, created when missing); CheckError naming --history."""
    try:
        if folder.is_symlink() or (folder.exists() and not folder.is_dir()):
            raise CheckError("is not a folder (or is a link)", path=folder, field="--history",
                             hint="give a folder that holds only s2r fleet histories")
        folder.mkdir(parents=True, exist_ok=True)
    except S2RError:
        raise
    except OSError as exc:
        raise CheckError(f"cannot create folder: {exc.strerror}", path=folder, field="--history",
                         hint="choose a writable location") from None
    with contextlib.suppress(OSError):
        return folder.resolve()
    return folder


def _days(points: list[dict[str, Any]]) -> list[float]:
    times = [dt.datetime.fromisoformat(p["time"]) for p in points]
    return [(t - times[0]).total_seconds() / 86400.0 for t in times]


def trend_summary(points: list[dict[str, Any]], tolerance_deg: dict[str, float]) -> dict[str, Any]:
    """Per axis, the drift rate (deg per day, a least-squares line over the runs that estimated the axis) and, when
    it moves towards the tolerance, the days left until it crosses it at that rate (None: not heading there, or
    fewer than two estimates). ``points`` as :func:`robot_trends` gives them, oldest first."""
    rate: dict[str, float | None] = {}
    days_left: dict[str, float | None] = {}
    try:
        days = _days(points)
    except (KeyError, TypeError, ValueError):
        return {"runs": len(points), "rate_deg_per_day": {}, "days_to_tolerance": {}}
    for axis in AXES:
        pairs = [(d, p["rotation_error_deg"][axis]) for d, p in zip(days, points, strict=True)
                 if p["rotation_error_deg"].get(axis) is not None]
        rate[axis] = days_left[axis] = None
        if len(pairs) < 2 or pairs[-1][0] - pairs[0][0] <= 0:
            continue
        t = [d for d, _ in pairs]
        v = [e for _, e in pairs]
        mean_t, mean_v = sum(t) / len(t), sum(v) / len(v)
        slope = sum((a - mean_t) * (b - mean_v) for a, b in pairs) / sum((a - mean_t) ** 2 for a in t)
        rate[axis] = slope
        tol = tolerance_deg.get(axis)
        last = v[-1]
        if tol and slope != 0 and math.copysign(1.0, slope) == math.copysign(1.0, last) and abs(last) < tol:
            days_left[axis] = (tol - abs(last)) / abs(slope)
    return {"runs": len(points), "rate_deg_per_day": rate, "days_to_tolerance": days_left}

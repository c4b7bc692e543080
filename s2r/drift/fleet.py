"""``s2r fleet check FLEET.yaml``: the drift check of every robot, one task each on the executor seam.

FLEET.yaml::

    robots:
      - name: r01                      # unique; letters, digits, _ . -
        profile: profiles/r01.yaml     # a path (relative to FLEET.yaml) or a shipped profile name
        recording: logs/r01            # a folder, or a mapping:
      - name: r02
        profile: realsense_d435_848x480
        recording: {bag: logs/r02.bag, left_topic: /cam/left/image_raw, right_topic: /cam/right/image_raw}
      - name: r03
        profile: r03.yaml
        recording: {left: "logs/r03/left_*.png", right: "logs/r03/right_*.png", max_frames: 10}

A robot whose files are broken or missing is reported as ``failed`` with the reason, never fatal; FLEET.yaml
itself being malformed is bad input (CheckError, exit 2). Tasks run in worker processes (local pool or Dask),
and return plain data; the parent writes every file. Paths are made absolute before they are sent: the workers
of a ``--scheduler`` cluster must see the profiles and recordings at the same paths (a shared file system).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from s2r.drift.check import CheckSettings, check_drift
from s2r.drift.report import check_report_html
from s2r.drift.source import StereoSource, profile_sizes, read_pairs
from s2r.errors import CheckError, S2RError
from s2r.executor import open_runner
from s2r.fileio import read_text_file
from s2r.names import NAME_HINT, is_safe_name
from s2r.progress import ProgressCallback, report
from s2r.safeparse import parse_yaml

__all__ = ["MAX_FLEET_CHARS", "MAX_ROBOTS", "SEVERITY", "RobotJob", "load_fleet", "run_fleet", "run_robot"]

#: Verdicts from most to least severe (the summary's sort order).
SEVERITY = ("failed", "drifted", "cannot tell", "good")
#: Names the fleet's own output files take in -o (compared case-insensitively, as some file systems do).
RESERVED_NAMES = frozenset({"index.html", "summary.json"})
#: Largest fleet file (characters) and number of robots in one run.
MAX_FLEET_CHARS = 4_000_000
MAX_ROBOTS = 10_000
_RECORDING_KEYS = {"folder", "left", "right", "bag", "left_topic", "right_topic", "max_frames"}


@dataclass(frozen=True)
class RobotJob:
    """One robot's check: its name, profile (name or absolute path), recording and settings."""

    name: str
    profile: str
    source: StereoSource
    settings: CheckSettings


def _resolve(base: Path, value: Any, where: str, path: Path) -> Path:
    if not isinstance(value, str) or not value:
        raise CheckError("must be a non-empty path", path=path, field=where, hint="write a relative or absolute path")
    return Path(value) if Path(value).is_absolute() else base / value


def _source(base: Path, value: Any, where: str, path: Path, max_frames: int) -> StereoSource:
    if isinstance(value, str):
        return StereoSource(folder=_resolve(base, value, where, path), max_frames=max_frames)
    if not isinstance(value, dict) or not value.keys() <= _RECORDING_KEYS:
        extra = sorted(set(value) - _RECORDING_KEYS) if isinstance(value, dict) else []
        raise CheckError(f"unknown keys {extra}" if extra else "must be a folder or a mapping", path=path, field=where,
                         hint=f"a folder path, or a mapping with {', '.join(sorted(_RECORDING_KEYS))}")
    frames = value.get("max_frames", max_frames)
    if not isinstance(frames, int) or isinstance(frames, bool) or frames < 1:
        raise CheckError("max_frames must be a whole number of at least 1", path=path, field=f"{where}.max_frames")
    if "bag" in value:
        return StereoSource(bag=_resolve(base, value["bag"], f"{where}.bag", path), left_topic=value.get("left_topic"),
                            right_topic=value.get("right_topic"), max_frames=frames)
    if "left" in value or "right" in value:
        globs = [str(_resolve(base, value.get(k), f"{where}.{k}", path)) for k in ("left", "right")]
        return StereoSource(left_glob=globs[0], right_glob=globs[1], max_frames=frames)
    return StereoSource(folder=_resolve(base, value.get("folder"), f"{where}.folder", path), max_frames=frames)


def _profile(base: Path, value: Any, where: str, path: Path) -> str:
    if not isinstance(value, str) or not value:
        raise CheckError("must be a profile name or path", path=path, field=where)
    looks_like_path = "/" in value or value.endswith((".yaml", ".yml"))
    return str(_resolve(base, value, where, path)) if looks_like_path else value


def load_fleet(path: str | Path, *, settings: CheckSettings, max_frames: int = 20) -> list[RobotJob]:
    """The robots of FLEET.yaml; CheckError naming the file and entry when it is malformed."""
    path = Path(path)
    text = read_text_file(path, error=CheckError)
    if len(text) > MAX_FLEET_CHARS:  # before parsing: PyYAML takes minutes and gigabytes on tens of megabytes
        raise CheckError(f"is {len(text) / 1e6:.1f} MB; a fleet file is at most {MAX_FLEET_CHARS / 1e6:g} MB",
                         path=path, hint=f"split the fleet into files of at most {MAX_ROBOTS} robots")
    data = parse_yaml(text, path=path, error=CheckError)
    robots = data.get("robots") if isinstance(data, dict) else None
    if not isinstance(robots, list) or not robots:
        raise CheckError("needs a non-empty list 'robots'", path=path, field="robots",
                         hint="robots: [{name: r01, profile: r01.yaml, recording: logs/r01}]")
    if len(robots) > MAX_ROBOTS:
        raise CheckError(f"lists {len(robots)} robots; one run checks at most {MAX_ROBOTS}", path=path,
                         field="robots", hint="split the fleet into several files (one run each)")
    base, jobs, seen = path.absolute().parent, [], set[str]()  # absolute: workers of a --scheduler have another cwd
    for k, entry in enumerate(robots):
        where = f"robots[{k}]"
        if not isinstance(entry, dict) or not {"name", "profile", "recording"} <= entry.keys():
            raise CheckError("each robot needs name, profile and recording", path=path, field=where)
        name = entry["name"]
        if not is_safe_name(name) or name.lower() in seen | RESERVED_NAMES:
            raise CheckError(f"bad or repeated name {name!r}", path=path, field=f"{where}.name",
                             hint=f"unique names (ignoring case) of {NAME_HINT}, "
                             "nor index.html or summary.json: they name the report folders")
        seen.add(name.lower())
        jobs.append(RobotJob(name, _profile(base, entry["profile"], f"{where}.profile", path),
                             _source(base, entry["recording"], f"{where}.recording", path, max_frames), settings))
    return jobs


def _one_thread_per_worker() -> None:
    """Inside a Dask worker (a spawned process, one task at a time), OpenCV uses one thread: each worker then
    takes one core, and adding workers adds throughput instead of contention. Never in a forked child or the
    caller's own process (``cv2.setNumThreads`` after a fork can hang)."""
    try:
        from distributed import get_worker

        get_worker()
    except (ImportError, ValueError):
        return
    import cv2

    cv2.setNumThreads(1)


def run_robot(job: RobotJob) -> dict[str, Any]:
    """One robot's check as plain data (runs in a worker): the ``--json`` fields, ``html``, and its verdict.

    Broken inputs become ``verdict: failed`` with the one-line reason; they never raise.
    """
    from s2r.registry import load_profile

    _one_thread_per_worker()
    try:
        profile = load_profile(job.profile)
        result = check_drift(profile, read_pairs(job.source, sizes=profile_sizes(profile)), settings=job.settings)
    except S2RError as exc:
        return {"name": job.name, "verdict": "failed", "reasons": [exc.one_line()], "html": None}
    except Exception as exc:  # a bug must not take the fleet down; it is named as one
        detail = " ".join(str(exc).split())[:200]
        return {"name": job.name, "verdict": "failed", "html": None,
                "reasons": [f"internal error ({type(exc).__name__}: {detail}); this is a bug in s2r"]}
    row = {"name": job.name, **result.as_dict(), "html": check_report_html(result, source=job.source.describe())}
    return row


def run_fleet(jobs: list[RobotJob], *, workers: int, scheduler: str | None = None,
              progress: ProgressCallback | None = None) -> list[dict[str, Any]]:
    """Every robot's :func:`run_robot` row, one task each on Dask (a scheduler, else a local cluster of
    ``workers`` processes), sorted most severe first (then by name)."""
    rows: list[dict[str, Any]] = []
    report(progress, 0, len(jobs), "checking robots")
    with open_runner(workers=min(workers, len(jobs)), scheduler=scheduler, dask=True) as runner:
        for outcome in runner.as_completed(run_robot, jobs):
            if outcome.error is not None:  # the task itself died (a worker lost): the robot is named, not judged
                rows.append({"name": outcome.item.name, "verdict": "failed", "html": None,
                             "reasons": [f"the check did not finish: {type(outcome.error).__name__}: "
                                         f"{' '.join(str(outcome.error).split())[:200]}"]})
            else:
                rows.append(outcome.result or {})
            report(progress, len(rows), len(jobs), "checking robots")
    return sorted(rows, key=lambda r: (SEVERITY.index(r["verdict"]), r["name"]))

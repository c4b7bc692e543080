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
      - name: r04
        profile: r04.yaml
        recording: https://logs.example.org/r04/2026-12-05/   # a URL (http(s)://, s3://, file://): a folder
      - name: r05
        profile: r05.yaml
        recording: {bag: s3://fleet-logs/r05.bag, left_topic: /l, right_topic: /r}   # or one bag file

A robot whose files are broken or missing is reported as ``failed`` with the reason, never fatal; FLEET.yaml
itself being malformed is bad input (CheckError, exit 2). Tasks run in worker processes (local pool or Dask),
and return plain data; the parent writes every file. Paths are made absolute before they are sent: the workers
of a ``--scheduler`` cluster must see the profiles and local recordings at the same paths (a shared file
system); a recording given as a URL is read by the worker itself (:mod:`s2r.drift.fleet_remote`).

Each row carries ``recording``: where it was read, the number of pairs and a SHA-256 of their names and pixels
(the recording's identity in the history).
"""

from __future__ import annotations

import contextlib
import hashlib
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from s2r.drift.check import CheckSettings, check_drift
from s2r.drift.fleet_remote import RemoteRecording, local_source
from s2r.drift.fleet_store import Journal, job_key
from s2r.drift.report import check_report_html
from s2r.drift.source import GreyPair, StereoSource, profile_sizes, read_pairs
from s2r.errors import CheckError, S2RError
from s2r.executor import open_runner
from s2r.fileio import TEMP_PREFIX, protect_input, read_text_file
from s2r.names import NAME_HINT, is_safe_name
from s2r.progress import ProgressCallback, report
from s2r.recordings import skipped_fields
from s2r.recordings.remote import RemoteError, check_url, is_url
from s2r.safeparse import parse_yaml

__all__ = ["MAX_FLEET_CHARS", "MAX_ROBOTS", "SEVERITY", "FleetRun", "RobotJob", "load_fleet", "run_fleet",
           "run_robot"]

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
    source: StereoSource | RemoteRecording
    settings: CheckSettings


def _resolve(base: Path, value: Any, where: str, path: Path) -> Path:
    if not isinstance(value, str) or not value:
        raise CheckError("must be a non-empty path", path=path, field=where, hint="write a relative or absolute path")
    return Path(value) if Path(value).is_absolute() else base / value


def _url(value: Any, where: str, path: Path) -> str | None:
    """``value`` when it is a URL of a scheme s2r reads; None when it is no URL; CheckError for another scheme."""
    if not isinstance(value, str) or not is_url(value):
        return None
    try:
        return check_url(value)
    except RemoteError as exc:
        raise CheckError(exc.message, path=path, field=where, hint=exc.hint) from None


def _source(base: Path, value: Any, where: str, path: Path, max_frames: int) -> StereoSource | RemoteRecording:
    if isinstance(value, str):
        url = _url(value, where, path)
        if url is not None:
            return RemoteRecording(url, max_frames=max_frames)
        return StereoSource(folder=_resolve(base, value, where, path), max_frames=max_frames)
    if not isinstance(value, dict) or not value.keys() <= _RECORDING_KEYS:
        extra = sorted(set(value) - _RECORDING_KEYS) if isinstance(value, dict) else []
        raise CheckError(f"unknown keys {extra}" if extra else "must be a folder or a mapping", path=path, field=where,
                         hint=f"a folder path, or a mapping with {', '.join(sorted(_RECORDING_KEYS))}")
    frames = value.get("max_frames", max_frames)
    if not isinstance(frames, int) or isinstance(frames, bool) or frames < 1:
        raise CheckError("max_frames must be a whole number of at least 1", path=path, field=f"{where}.max_frames")
    remote = _remote(value, where, path, frames)
    if remote is not None:
        return remote
    if "bag" in value:
        return StereoSource(bag=_resolve(base, value["bag"], f"{where}.bag", path), left_topic=value.get("left_topic"),
                            right_topic=value.get("right_topic"), max_frames=frames)
    if "left" in value or "right" in value:
        globs = [str(_resolve(base, value.get(k), f"{where}.{k}", path)) for k in ("left", "right")]
        return StereoSource(left_glob=globs[0], right_glob=globs[1], max_frames=frames)
    return StereoSource(folder=_resolve(base, value.get("folder"), f"{where}.folder", path), max_frames=frames)


def _remote(value: dict[str, Any], where: str, path: Path, frames: int) -> RemoteRecording | None:
    """A mapping's recording at a URL (``bag: URL`` with the topics, or ``folder: URL``); None when local."""
    urls = {k: _url(value.get(k), f"{where}.{k}", path) for k in ("bag", "folder", "left", "right")}
    if urls["left"] or urls["right"]:
        raise CheckError("globs of URLs are not read", path=path, field=where,
                         hint="give the recording folder's URL (recording: https://host/logs/r01/)")
    if urls["bag"]:
        if not value.get("left_topic") or not value.get("right_topic"):
            raise CheckError("a bag needs left_topic and right_topic", path=path, field=where)
        return RemoteRecording(urls["bag"], max_frames=frames, left_topic=str(value["left_topic"]),
                               right_topic=str(value["right_topic"]))
    return RemoteRecording(urls["folder"], max_frames=frames) if urls["folder"] else None


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
        _protect(jobs[-1])
    return jobs


def _protect(job: RobotJob) -> None:
    """The robot's profile and recording are inputs of the run: ``-o DIR --force`` never replaces a folder holding
    them (the workers would find them gone, and the old folder is removed once the run is published)."""
    from s2r.registry import resolve_profile

    with contextlib.suppress(S2RError):  # a bad profile is the robot's failure, reported by its worker
        protect_input(resolve_profile(job.profile))
    given = [] if isinstance(job.source, RemoteRecording) else [getattr(job.source, k) for k in
                                                                 ("folder", "bag", "left_glob", "right_glob")]
    for value in given:
        if value is not None:
            protect_input(value)


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


def _identified(pairs: Iterator[GreyPair], identity: dict[str, Any]) -> Iterator[GreyPair]:
    """``pairs`` passed through, their names and pixels hashed into ``identity`` (``pairs``, ``sha256``)."""
    digest = hashlib.sha256()
    for name, left, right in pairs:
        for part in (name.encode("utf-8"), str(left.shape).encode(), left.tobytes(), right.tobytes()):
            digest.update(part)
        identity["pairs"] = identity.get("pairs", 0) + 1
        identity["sha256"] = digest.hexdigest()
        yield name, left, right


def _check(job: RobotJob, identity: dict[str, Any], skipped: list[str]) -> Any:
    from s2r.registry import load_profile

    profile = load_profile(job.profile)
    if isinstance(job.source, RemoteRecording):  # read by this worker into a copy that goes with the check
        with tempfile.TemporaryDirectory(prefix=TEMP_PREFIX) as tmp:
            source = local_source(job.source, Path(tmp))
            pairs = _identified(read_pairs(source, sizes=profile_sizes(profile), skipped=skipped), identity)
            return check_drift(profile, pairs, settings=job.settings)
    pairs = _identified(read_pairs(job.source, sizes=profile_sizes(profile), skipped=skipped), identity)
    return check_drift(profile, pairs, settings=job.settings)


def run_robot(job: RobotJob) -> dict[str, Any]:
    """One robot's check as plain data (runs in a worker): the ``--json`` fields, ``html``, its verdict and
    ``recording`` (where it was read, pairs, SHA-256).

    Broken inputs become ``verdict: failed`` with the one-line reason; they never raise.
    """
    _one_thread_per_worker()
    identity: dict[str, Any] = {"source": job.source.describe(), "pairs": 0, "sha256": None}
    skipped: list[str] = []
    try:
        result = _check(job, identity, skipped)
    except S2RError as exc:
        return {"name": job.name, "verdict": "failed", "reasons": [exc.one_line()], "html": None,
                "recording": identity}
    except Exception as exc:  # a bug must not take the fleet down; it is named as one
        detail = " ".join(str(exc).split())[:200]
        return {"name": job.name, "verdict": "failed", "html": None, "recording": identity,
                "reasons": [f"internal error ({type(exc).__name__}: {detail}); this is a bug in s2r"]}
    return {"name": job.name, **result.as_dict(), **skipped_fields(skipped), "recording": identity,
            "html": check_report_html(result, source=job.source.describe())}


@dataclass
class FleetRun:
    """Every robot's row (most severe first), the Dask workers lost during the run, and the robots whose rows
    came from the journal of an interrupted run (``--resume``)."""

    rows: list[dict[str, Any]]
    lost_workers: list[str] = field(default_factory=list)
    resumed: list[str] = field(default_factory=list)


def _unfinished(job: RobotJob, error: BaseException) -> dict[str, Any]:
    return {"name": job.name, "verdict": "failed", "html": None, "recording": {"source": job.source.describe()},
            "reasons": [f"the check did not finish: {type(error).__name__}: {' '.join(str(error).split())[:200]}"]}


def run_fleet(jobs: list[RobotJob], *, workers: int, scheduler: str | None = None,
              progress: ProgressCallback | None = None, journal: Journal | None = None,
              resume: bool = False) -> FleetRun:
    """Every robot's :func:`run_robot` row, one task each on Dask (a scheduler, else a local cluster of
    ``workers`` processes), sorted most severe first (then by name).

    Args:
        journal: where each finished row is persisted as it arrives (atomically).
        resume: take the rows the journal already holds for unchanged jobs instead of checking them again.
    """
    keys = {job.name: job_key(job) for job in jobs}
    finished = journal.finished(keys) if journal is not None and resume else {}
    todo = [job for job in jobs if job.name not in finished]
    run = FleetRun(rows=list(finished.values()), resumed=sorted(finished))
    report(progress, len(run.rows), len(jobs), "checking robots")
    if todo:
        with open_runner(workers=min(workers, len(todo)), scheduler=scheduler, dask=True) as runner:
            for outcome in runner.as_completed(run_robot, todo):
                row = _unfinished(outcome.item, outcome.error) if outcome.error is not None else outcome.result
                run.rows.append(row or {})
                if journal is not None and outcome.error is None:  # a task lost with its worker is run again
                    journal.add(row or {}, keys[outcome.item.name])
                run.lost_workers = list(runner.lost_workers)
                report(progress, len(run.rows), len(jobs), "checking robots")
    run.rows.sort(key=lambda r: (SEVERITY.index(r["verdict"]), r["name"]))
    return run

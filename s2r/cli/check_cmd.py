"""``s2r check`` and ``s2r fleet check``: is a stereo calibration still right, from ordinary recordings.

Exit codes: 0 good (every robot good), 1 drifted or cannot tell (any robot not good, or failed), 2 bad input.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import sys
from pathlib import Path
from typing import Any

from s2r.cli._common import (
    ProgressBar,
    add_force,
    add_jobs,
    add_json,
    add_profile_positional,
    check_jobs,
    load_profile,
    print_json,
    profile_argument,
    to_jsonable,
)
from s2r.cli._recording import add_recording_arguments, spec_from_args
from s2r.errors import CheckError

__all__ = ["register"]


_MAX_FRAMES_HELP = "pairs used, spread over the recording (default 20)"


def _add_settings(parser: argparse.ArgumentParser, *, max_frames: bool = True) -> None:
    parser.add_argument("--tolerance", type=float, default=0.05, metavar="DEG",
                        help="rotation drift tolerated per axis, degrees (default 0.05)")
    parser.add_argument("--tolerance-px", type=float, default=0.5, metavar="PX",
                        help="rows of mismatch tolerated, p95 over the image, pixels (default 0.5)")
    if max_frames:
        parser.add_argument("--max-frames", type=int, default=20, metavar="N", help=_MAX_FRAMES_HELP)


def register(sub: Any) -> None:
    """Add ``check`` and ``fleet check``."""
    p = sub.add_parser(
        "check", help="is a stereo calibration still right? (no target: ordinary scenes)",
        description="Rectify ordinary stereo pairs with the profile, match features, and fit the relative-rotation "
        "error that explains their vertical disparity. Verdict good / drifted / cannot tell; --fix writes the "
        "profile with the rotation re-estimated. Exit 0 good, 1 drifted or cannot tell, 2 bad input.")
    add_profile_positional(p, help="profile name or path (or give it as --profile)")
    add_recording_arguments(p, max_frames_default=20, max_frames_help=_MAX_FRAMES_HELP, what="ordinary stereo pairs")
    _add_settings(p, max_frames=False)
    add_jobs(p, default=None, help="feature-matching processes (default: all cores)")
    p.add_argument("--report", type=Path, metavar="DIR", help="write DIR/check.html")
    p.add_argument("--fix", action="store_true", help="write the corrected profile to -o")
    p.add_argument("-o", "--output", type=Path, help="--fix: corrected profile YAML to write")
    add_json(p)
    add_force(p)
    p.set_defaults(func=_cmd_check)
    fleet = sub.add_parser("fleet", help="drift checks of many robots on Dask",
                           description="Run s2r check for every robot of a fleet file.")
    fleet_sub = fleet.add_subparsers(dest="fleet_action", required=True, metavar="ACTION")
    fc = fleet_sub.add_parser(
        "check", help="check every robot of FLEET.yaml, one Dask task each",
        description="Each robot (name, profile, recording) is one task on Dask's distributed scheduler: a local "
        "cluster of --jobs processes, or --scheduler tcp://host:8786. Writes DIR/index.html, DIR/summary.json "
        "and DIR/NAME/check.html. Exit 0 every robot good, 1 any not good, 2 FLEET.yaml is bad input.")
    fc.add_argument("fleet_file", type=Path, metavar="FLEET.yaml")
    fc.add_argument("-o", "--output", type=Path, required=True, metavar="DIR", help="output folder")
    fc.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (default: a local cluster)")
    add_jobs(fc, default=2, help="local cluster worker processes (default 2)")
    fc.add_argument("--resume", action="store_true",
                    help="check only the robots an interrupted run into the same -o DIR did not finish")
    fc.add_argument("--history", type=Path, metavar="HDIR",
                    help="keep this run's results in HDIR and show each robot's trend over the runs kept there")
    _add_settings(fc)
    add_json(fc)
    add_force(fc)
    fc.set_defaults(func=_cmd_fleet)


def _settings(args: argparse.Namespace) -> Any:
    from s2r.drift.check import CheckSettings

    if not 0.0 < args.tolerance <= 10.0:  # NaN fails too
        raise CheckError(f"must be between 0 and 10 degrees, got {args.tolerance}", field="--tolerance",
                         hint="e.g. 0.05")
    if args.max_frames < 1:
        raise CheckError(f"must be at least 1, got {args.max_frames}", field="--max-frames", hint="e.g. 20")
    if not 0.0 < args.tolerance_px <= 100.0:
        raise CheckError(f"must be between 0 and 100 pixels, got {args.tolerance_px}", field="--tolerance-px",
                         hint="e.g. 0.5")
    return CheckSettings(tolerance_deg=(args.tolerance,) * 3, tolerance_px=args.tolerance_px)


def _refuse_reversed(args: argparse.Namespace) -> None:
    """``s2r check logs/run1 real.yaml``: a folder where the profile goes and a profile file where the recording
    goes is the arguments the wrong way round."""
    first, second = Path(args.profile), args.recording
    if second is not None and first.is_dir() and second.suffix.lower() in (".yaml", ".yml") and second.is_file():
        raise CheckError("the arguments look reversed: the profile comes first, then the recording",
                         path=first, field="PROFILE", hint=f"s2r check {second} {first}")


def _source(args: argparse.Namespace) -> Any:
    from s2r.drift.source import StereoSource

    return StereoSource(spec_from_args(args, max_frames=False).check(error=CheckError), max_frames=args.max_frames)


def _cmd_check(args: argparse.Namespace) -> int:
    from s2r.drift.check import run_check
    from s2r.drift.source import profile_sizes, read_pairs
    from s2r.executor import usable_cores
    from s2r.fileio import atomic_write_text, check_output_free, prepare_output_dir
    from s2r.recordings import skipped_fields

    args.profile = profile_argument(args, command="check")  # with --profile, the positional may be the FOLDER
    if args.fix != (args.output is not None):
        raise CheckError("--fix and -o go together", field="--fix", hint="pass --fix -o corrected.yaml")
    _refuse_reversed(args)
    settings, source = _settings(args), _source(args)
    check_jobs(args.jobs, CheckError)
    profile = load_profile(args.profile)
    if args.output is not None:
        check_output_free(args.output, force=args.force)
    if args.report is not None:
        prepare_output_dir(args.report, force=args.force)
    bar = ProgressBar(enabled=not (args.quiet or args.json))
    skipped: list[str] = []
    pairs = read_pairs(source, sizes=profile_sizes(profile), skipped=skipped)
    checked = run_check(profile, pairs, settings=settings, progress=bar, total=source.max_frames,
                        jobs=min(args.jobs or usable_cores(), source.max_frames))
    result = checked.result
    steps = _next_steps(args, result)
    if args.json:
        print_json({**result.as_dict(), **skipped_fields(skipped), "next_steps": steps})
    else:
        print("\n".join([*_summary(result), *(f"  next: {s}" for s in steps)]))
    if args.report is not None:
        from s2r.drift.report import check_report_html

        path = atomic_write_text(args.report / "check.html", check_report_html(result, source=source.describe()),
                                 force=True)
        print(f"report: {path}", file=sys.stderr if args.json else sys.stdout)
    if args.fix:
        _write_fix(args, checked, settings, source.describe())
    return 0 if result.verdict == "good" else 1


def _next_steps(args: argparse.Namespace, result: Any) -> list[str]:
    from s2r.drift.verdict import Verdict, next_steps

    recording = str(args.recording) if args.recording is not None else "RECORDING"
    verdict = Verdict(result.verdict, result.reasons, result.decided_by, result.unresolved)
    return next_steps(verdict, profile=str(args.profile), recording=recording, swapped=result.swap is not None)


def _write_fix(args: argparse.Namespace, checked: Any, settings: Any, source: str) -> None:
    from s2r.drift.fix import plan_fix
    from s2r.formats.s2r_yaml import dump_profile

    fix = plan_fix(checked, settings=settings, source=source)
    dump_profile(fix.profile, args.output, force=args.force)
    out = sys.stderr if args.json else sys.stdout
    for line in fix.lines():
        print(line, file=out)
    print(f"wrote {args.output}: rotation corrected, intrinsics and baseline kept", file=out)


def _summary(result: Any) -> list[str]:
    from s2r.drift.check import AXES, BLIND_SPOTS

    lines = [f"{result.profile}: {result.verdict.upper()} - {'; '.join(result.reasons)}",
             f"  {result.matches} matches in {len(result.frames)} frames, robust residual {result.residual_px:.3f} px",
             *([f"  {result.downscaled}"] if result.downscaled else []),
             "  rotation error of the right camera (deg, about its optical axes; R_true = dR R_profile):"]
    lines += [f"    {a:<6}{o:+.4f} +/- {s:.4f}  (tolerance {t:g})" if math.isfinite(o) else
              f"    {a:<6}not estimated  (tolerance {t:g})" for a, o, s, t in
              zip(AXES, result.omega_deg, result.sigma_deg, result.tolerance_deg, strict=True)]
    if not all(math.isfinite(o) for o in result.omega_deg):
        return [*lines, f"  {BLIND_SPOTS}"]
    v = result.vertical_px
    lines.append(f"  rows of mismatch it leaves: median {v['median']:.2f} px, p95 {v['p95']:.2f} px "
                 f"(tolerance {result.tolerance_px:g} px p95; {result.decided_by or 'not judged'})")
    lines.append("  depth bias at the centre (from yaw): " + ", ".join(
        f"{c['depth_error_pct']:+.2f} +/- {c['depth_error_sigma_pct']:.2f} % at {c['distance_m']:g} m"
        for c in result.depth_cost))
    lines.append(f"  {BLIND_SPOTS}")
    return lines


def _cmd_fleet(args: argparse.Namespace) -> int:
    from s2r.drift.fleet import load_fleet
    from s2r.drift.fleet_store import check_history_folder

    settings = _settings(args)
    check_jobs(args.jobs, CheckError, local=args.scheduler is None,
               more="for more, run a Dask cluster and pass --scheduler")
    jobs = load_fleet(args.fleet_file, settings=settings, max_frames=args.max_frames)
    history = check_history_folder(args.history) if args.history is not None else None
    journal = _fleet_output(args)
    with _signals_interrupt():
        try:
            run = _run_fleet(args, jobs, journal)
        except KeyboardInterrupt:
            done = len(journal.finished({j.name: _key(j) for j in jobs}))
            print(f"interrupted: {done} of {len(jobs)} robots finished, kept in {journal.folder}; nothing else was "
                  "written (run the same command with --resume to check the others)", file=sys.stderr)
            raise
    rows = run.rows
    trends = _publish_fleet(args, run, journal, history)
    if args.json:
        print_json({"robots": _summary_rows(rows, trends), "counts": _counts(rows), "output": str(args.output),
                    "lost_workers": run.lost_workers, "resumed": run.resumed})
    else:
        for r in rows:
            print(f"{r['verdict'].upper():<12} {r['name']:<20} {'; '.join(r['reasons'])}")
        print(f"{len(rows)} robots: " + ", ".join(f"{n} {v}" for v, n in _counts(rows).items() if n))
        if run.lost_workers:
            print(f"{len(run.lost_workers)} Dask worker(s) lost during the run ({', '.join(run.lost_workers)}); "
                  "their robots were run again on the others")
    return 0 if all(r["verdict"] == "good" for r in rows) else 1


def _key(job: Any) -> str:
    from s2r.drift.fleet_store import job_key

    return job_key(job)


def _run_fleet(args: argparse.Namespace, jobs: list[Any], journal: Any) -> Any:
    from s2r.drift.fleet import run_fleet

    bar = ProgressBar(enabled=not (args.quiet or args.json))
    return run_fleet(jobs, workers=args.jobs, scheduler=args.scheduler, progress=bar, journal=journal,
                     resume=args.resume)


def _fleet_output(args: argparse.Namespace) -> Any:
    """The output folder, created (exclusively unless --force), and its journal of finished robots.

    Without --resume a folder holding files is refused unless --force (then an old journal is dropped); with
    --resume it must hold an interrupted run's journal, and other files only with --force."""
    from s2r.drift.fleet_store import JOURNAL, Journal
    from s2r.fileio import check_output_dir

    out = Path(args.output)
    if not args.resume:  # the folder is made when the first robot finishes (none for a cluster never reached)
        check_output_dir(out, force=args.force)
        if out.is_dir() and any(out.iterdir()):  # --force: replaced whole (an old robot's folder must not stay)
            from s2r.fileio import prepare_output_dir

            prepare_output_dir(out, force=args.force)
        Journal(out).remove()
        return Journal(out)
    journal = Journal(out)
    if out.is_symlink() or not journal.exists():
        raise CheckError("holds no interrupted fleet run to resume", path=out, field="--resume",
                         hint="run without --resume (or give the -o folder of the interrupted run)")
    others = [p.name for p in out.iterdir() if p.name != JOURNAL]
    if others and not args.force:
        raise CheckError(f"holds other files ({', '.join(sorted(others)[:3])}); nothing was overwritten", path=out,
                         hint="pass --force to replace them when the run is published")
    return journal


@contextlib.contextmanager
def _signals_interrupt() -> Any:
    """SIGTERM ends the run as Ctrl-C does (KeyboardInterrupt: workers, cluster and temporaries closed)."""
    import signal

    def interrupt(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    try:
        before = signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread (an in-process caller): leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, before)


def _summary_rows(rows: list[dict[str, Any]], trends: dict[str, Any]) -> list[dict[str, Any]]:
    return [{**{k: v for k, v in r.items() if k != "html"}, **({"trend": trends[r["name"]]} if r["name"] in trends
                                                                else {})} for r in rows]


def _counts(rows: list[dict[str, Any]]) -> dict[str, int]:
    from s2r.drift.fleet import SEVERITY

    return {v: sum(r["verdict"] == v for r in rows) for v in SEVERITY}


def _publish_fleet(args: argparse.Namespace, run: Any, journal: Any, history: Path | None) -> dict[str, Any]:
    """Publish the outputs (whole or not at all), then add the run to the history and drop the journal; the
    robots' trends (empty without --history)."""
    import datetime as dt

    from s2r.drift.fleet_store import history_entry, robot_trends, trend_summary, write_history

    entry = history_entry(run.rows, when=dt.datetime.now(dt.timezone.utc))
    trends: dict[str, Any] = {}
    if history is not None:
        for name, points in robot_trends(history, entry).items():
            trends[name] = {"points": points, **trend_summary(points, points[-1].get("tolerance_deg") or {})}
    _write_fleet(args, run, trends)
    if history is not None:
        path = write_history(history, entry)
        print(f"history: {path}", file=sys.stderr if args.json else sys.stdout)
    journal.remove()
    return trends


def _write_fleet(args: argparse.Namespace, run: Any, trends: dict[str, Any]) -> None:
    """DIR/index.html, DIR/summary.json and each robot's DIR/NAME/check.html + check.json, published whole or not
    at all (one :class:`~s2r.fileio.OutputBatch`: a write error leaves none of them)."""
    from s2r.drift.report import fleet_report_html
    from s2r.fileio import OutputBatch, prepare_output_dir

    out, rows = Path(args.output), run.rows
    if not out.is_dir():  # no robot was journalled (every row resumed, or none finished): made now
        prepare_output_dir(out, force=args.force)
    created: list[Path] = []
    try:
        with OutputBatch(force=args.force, root=out) as batch:
            for r in rows:
                data = {k: v for k, v in r.items() if k != "html"}
                folder = _robot_folder(out / r["name"], created)
                if r.get("html"):
                    batch.add_text(folder / "check.html", r["html"])
                    r["report"] = f"{r['name']}/check.html"
                batch.add_text(folder / "check.json", json.dumps(to_jsonable(data), indent=2))
            summary = {"robots": _summary_rows(rows, trends), "counts": _counts(rows),
                       "lost_workers": run.lost_workers, "resumed": run.resumed}
            batch.add_text(out / "summary.json", json.dumps(to_jsonable(summary), indent=2))
            batch.add_text(out / "index.html", fleet_report_html(
                rows, fleet_file=args.fleet_file, lost_workers=run.lost_workers, resumed=run.resumed,
                trends=trends))
            batch.publish()
    except BaseException:
        for folder in reversed(created):  # nothing half-published: the folders made for it go too
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise


def _robot_folder(folder: Path, created: list[Path]) -> Path:
    """``folder`` as a real folder (made now and noted in ``created``, or already one with --force)."""
    try:
        folder.mkdir()
        created.append(folder)
    except FileExistsError:
        if folder.is_symlink() or not folder.is_dir():
            raise CheckError("is in the way of a robot's report folder (a file or a link); nothing was written",
                             path=folder, hint="remove it, or choose another output folder") from None
    except OSError as exc:
        raise CheckError(f"cannot create folder: {exc.strerror}", path=folder,
                         hint="choose a writable location") from None
    return folder

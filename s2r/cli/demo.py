"""``make demo``: the whole sim-to-real migration of a stereo camera, narrated, on shipped data.

1. lint the seed tutorial's dual-camera rig (its flaws) and derive the sim profile from the fixed rig;
2. calibrate the sample "recorded" set of a simulated RealSense D435 unit and compare with its truth;
3. validate sim against real (verdict, edits, depth error by distance) with an HTML report;
4. export the real profile as Gazebo sensor tags, re-derive the sim profile, validate again: it passes.

Run as ``python -m s2r.cli.demo [--quick] [-o DIR] [--report DIR]``; exits 0 when the story ends as it
should (flawed rig flagged, calibration within tolerance, first validation failing, closed loop passing).
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from s2r.cli import main as s2r_main
from s2r.formats.s2r_yaml import load_profile_file
from s2r.profile import StereoProfile

__all__ = ["DemoPaths", "calibration_errors", "run_demo"]

REPO = Path(__file__).resolve().parents[2]
UNIT_TRUTH = REPO / "calibration" / "d435_unit_truth.yaml"
SAMPLE_SET = REPO / "calibration" / "d435_unit_sample"
#: The calibration issue's tolerances on a synthetic rig: relative focal, absolute principal point (px),
#: relative baseline.
FOCAL_TOL_REL, CENTRE_TOL_PX, BASELINE_TOL_REL = 0.0015, 0.7, 0.002


def _rel(path: Path) -> str:
    """``path`` relative to the working folder when it is below it (shorter commands to read)."""
    return os.path.relpath(path) if path.resolve().is_relative_to(Path.cwd()) else str(path)


def sample_command(sample: Path) -> list[str]:
    """The command that (re)generates the sample set; ``make calibration-sample`` runs the same."""
    return ["render", "boards", _rel(UNIT_TRUTH), "--views", "24", "--seed", "7", "--noise", "2",
            "-o", _rel(sample), "--force"]


@dataclass
class DemoPaths:
    """Where the demo writes: profiles and Gazebo files in ``out``, HTML reports in ``report``."""

    out: Path
    report: Path
    sample: Path = SAMPLE_SET

    @property
    def sim(self) -> Path:
        return self.out / "sim_gazebo_dual_camera.yaml"

    @property
    def real(self) -> Path:
        return self.out / "real_d435_unit.yaml"

    @property
    def gazebo(self) -> Path:
        return self.out / "d435_unit_gz_sim.sdf"

    @property
    def matched(self) -> Path:
        return self.out / "sim_matched.yaml"


@dataclass
class DemoOutcome:
    """Exit codes of each step and whether the story ended as it should."""

    codes: dict[str, int] = field(default_factory=dict)
    calibration_ok: bool = False

    @property
    def ok(self) -> bool:
        expected = {"lint seed rig": 1, "lint fixed rig": 0, "from-urdf": 0, "calibrate": 0,
                    "validate sim vs real": 1, "export-gazebo": 0, "re-derive sim": 0, "validate closed loop": 0}
        return self.calibration_ok and all(self.codes.get(k) == v for k, v in expected.items())


def _run(title: str, argv: Sequence[str], outcome: DemoOutcome) -> int:
    print(f"\n$ s2r {shlex.join(argv)}", flush=True)
    code = s2r_main(list(argv))
    sys.stdout.flush()
    sys.stderr.flush()
    print(f"  -> exit {code}", flush=True)
    outcome.codes[title] = code
    return code


def _header(step: str, text: str) -> None:
    print(f"\n{'=' * 78}\n{step}  {text}\n{'=' * 78}", flush=True)


def calibration_errors(calibrated: StereoProfile, truth: StereoProfile) -> list[tuple[str, float, float, str, bool]]:
    """Rows ``(parameter, calibrated, true, error text, within tolerance)`` against the unit's truth."""
    rows: list[tuple[str, float, float, str, bool]] = []
    for side in ("left", "right"):
        cal, true = getattr(calibrated, side), getattr(truth, side)
        for name in ("fx_px", "fy_px"):
            a, b = getattr(cal, name), getattr(true, name)
            rel = (a - b) / b
            rows.append((f"{side} {name[:2]}", a, b, f"{100 * rel:+.3f} %", abs(rel) <= FOCAL_TOL_REL))
        for name in ("cx_px", "cy_px"):
            a, b = getattr(cal, name), getattr(true, name)
            rows.append((f"{side} {name[:2]}", a, b, f"{a - b:+.3f} px", abs(a - b) <= CENTRE_TOL_PX))
    rel = (calibrated.baseline_m - truth.baseline_m) / truth.baseline_m
    rows.append(("baseline mm", 1000 * calibrated.baseline_m, 1000 * truth.baseline_m, f"{100 * rel:+.3f} %",
                 abs(rel) <= BASELINE_TOL_REL))
    return rows


def _compare_with_truth(paths: DemoPaths, outcome: DemoOutcome) -> None:
    calibrated, truth = load_profile_file(paths.real), load_profile_file(UNIT_TRUTH)
    rows = calibration_errors(calibrated, truth)
    print(f"\nCalibrated profile against the unit's true profile ({_rel(UNIT_TRUTH)}):")
    print(f"  tolerances: focal {100 * FOCAL_TOL_REL:.2f} %, principal point {CENTRE_TOL_PX} px, "
          f"baseline {100 * BASELINE_TOL_REL:.1f} %")
    print(f"  {'parameter':<13}{'calibrated':>12}{'true':>12}{'error':>12}")
    for name, got, want, err, ok in rows:
        print(f"  {name:<13}{got:>12.3f}{want:>12.3f}{err:>12}  {'ok' if ok else 'OUT OF TOLERANCE'}")
    outcome.calibration_ok = all(row[4] for row in rows)


def _step_sim(paths: DemoPaths, outcome: DemoOutcome) -> None:
    _header("Step 1/4", "The simulated camera, from its robot description")
    print("The seed tutorial's dual-camera URDF, as written (right camera joint xyz = -0.1 0 0):")
    _run("lint seed rig", ["lint", _rel(REPO / "urdf" / "dual_camera.urdf.xacro")], outcome)
    print("\nThe same rig with the right camera 10 cm to the side (xyz = 0 -0.1 0):")
    fixed = _rel(REPO / "urdf" / "dual_camera_fixed.urdf.xacro")
    _run("lint fixed rig", ["lint", fixed], outcome)
    _run("from-urdf", ["profile", "from-urdf", fixed, "-o", str(paths.sim),
                       "--name", "gazebo_dual_camera", "--force"], outcome)
    s2r_main(["profile", "show", str(paths.sim)])


def _step_real(paths: DemoPaths, outcome: DemoOutcome, *, quick: bool) -> None:
    _header("Step 2/4", "The real camera, calibrated from chessboard images")
    if not (paths.sample / "left").is_dir():
        print("The sample set is not there yet; rendering it (make calibration-sample does the same):")
        _run("render sample set", sample_command(paths.sample), outcome)
    print("The sample set: a simulated RealSense D435 unit with its own focal lengths, principal points, "
          "distortion,\na 50.4 mm baseline and a 0.25 deg rotation, rendered with sensor noise (sigma 2 grey levels).")
    argv = ["calibrate", _rel(paths.sample), "--pattern", "9x6", "--square", "0.025", "-o", str(paths.real),
            "--force"]
    if not quick:
        argv += ["--report", str(paths.report / "calibration")]
    _run("calibrate", argv, outcome)
    if outcome.codes["calibrate"] == 0:
        _compare_with_truth(paths, outcome)


def _step_validate(paths: DemoPaths, outcome: DemoOutcome, *, quick: bool) -> None:
    _header("Step 3/4", "Is the simulated camera a faithful twin of the real one?")
    argv = ["validate", str(paths.sim), str(paths.real), "--report", str(paths.report), "--force"]
    _run("validate sim vs real", [*argv, "--quick"] if quick else argv, outcome)
    print("\nExit 1 is the expected answer: the tutorial's 60 deg, 640x480, 10 cm camera is not this D435.")


def _step_close_loop(paths: DemoPaths, outcome: DemoOutcome) -> None:
    _header("Step 4/4", "Close the loop: make the simulator match the real camera")
    _run("export-gazebo", ["profile", "export-gazebo", str(paths.real), "--format", "gz-sim", "-o",
                           str(paths.gazebo), "--force"], outcome)
    print(f"\n{paths.gazebo} holds the sensor blocks to paste into the robot's SDF; re-deriving the sim profile:")
    _run("re-derive sim", ["profile", "from-urdf", str(paths.gazebo), "--convention", "gz-sim", "-o",
                           str(paths.matched), "--name", "gazebo_matched_d435", "--force"], outcome)
    _run("validate closed loop", ["validate", str(paths.matched), str(paths.real), "--quick", "--report",
                                  str(paths.report / "closed_loop"), "--force"], outcome)


def run_demo(paths: DemoPaths, *, quick: bool = False) -> DemoOutcome:
    """Run the four steps, printing as it goes; returns every step's exit code."""
    outcome = DemoOutcome()
    _step_sim(paths, outcome)
    _step_real(paths, outcome, quick=quick)
    if outcome.codes.get("calibrate") == 0:
        _step_validate(paths, outcome, quick=quick)
        _step_close_loop(paths, outcome)
    return outcome


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m s2r.cli.demo``: exit 0 when the story ends as it should, 1 otherwise."""
    parser = argparse.ArgumentParser(prog="python -m s2r.cli.demo", description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="quick validations, no calibration report")
    parser.add_argument("-o", "--output", "--out", dest="out", default="demo_out",
                        help="folder for profiles and Gazebo files (--out is kept as an alias)")
    parser.add_argument("--report", default="demo_report", help="folder for the HTML reports")
    args = parser.parse_args(argv)
    start = time.monotonic()
    paths = DemoPaths(out=Path(args.out), report=Path(args.report))
    paths.out.mkdir(parents=True, exist_ok=True)
    outcome = run_demo(paths, quick=args.quick)
    _header("Done", f"in {time.monotonic() - start:.0f} s")
    report = paths.report.resolve() / "validation.html"
    print(f"Sim-vs-real report: {report}")
    if not args.quick:
        print(f"Calibration report: {paths.report.resolve() / 'calibration' / 'index.html'}")
    print(f"Closed-loop report: {paths.report.resolve() / 'closed_loop' / 'validation.html'}")
    verdict = "the story ended as it should" if outcome.ok else f"UNEXPECTED exit codes: {outcome.codes}"
    print(f"Demo: {verdict}.")
    print(_next_steps())
    return 0 if outcome.ok else 1


def _next_steps() -> str:
    """How to run s2r yourself after the demo: the installed entry point, with or without activating."""
    exe = Path(sys.executable).parent / "s2r"
    shown = os.path.relpath(exe) if exe.is_relative_to(Path.cwd()) else str(exe)
    activate = Path(shown).parent / "activate"
    return (f"\nRun s2r yourself: {shown} --help\n"
            f"  or once per shell: source {activate}   (then: s2r --help, python your_script.py)")


if __name__ == "__main__":
    sys.exit(main())

"""CLI start-up and names: light commands import no heavy library; a profile-name typo gets "did you mean".

Start-up time itself is measured by bench/bench_cli_startup.py (tests never assert wall-clock times): here a
fresh interpreter checks which modules ``import s2r.cli`` and a light command load.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.cli.sources_cmd import CONVENTION_CHOICES, EXPORT_FORMAT_CHOICES
from s2r.registry import did_you_mean, list_profiles

HEAVY = ("scipy", "cv2", "matplotlib", "pybullet", "rosbags", "xacro")


def _loaded_after(code: str) -> list[str]:
    probe = (f"import sys\n{code}\nimport json\n"
             f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    return list(json.loads(out.strip().splitlines()[-1]))


def test_importing_the_cli_loads_no_heavy_library() -> None:
    assert _loaded_after("import s2r.cli") == []


def test_profile_show_list_convert_load_no_heavy_library(tmp_path: Path) -> None:
    out = tmp_path / "camchain.yaml"
    code = ("from s2r.cli import main\nimport contextlib, io\nwith contextlib.redirect_stdout(io.StringIO()):\n"
            "    main(['profile', 'show', 'realsense_d435_848x480']); main(['profile', 'list'])\n"
            f"    main(['profile', 'convert', 'realsense_d435_848x480', '--to', 'kalibr', '-o', {str(out)!r}])")
    assert _loaded_after(code) == []
    assert out.is_file()


@pytest.mark.parametrize("argv", [["--help"], ["--version"], ["calibrate", "--help"], ["validate", "--help"]])
def test_help_and_version_load_no_heavy_library(argv: list[str]) -> None:
    """``s2r --help`` and friends parse and print only: no OpenCV, SciPy or Matplotlib (they exit via
    SystemExit, caught here so the probe can list what was loaded)."""
    code = ("from s2r.cli import main\nimport contextlib, io\nwith contextlib.redirect_stdout(io.StringIO()):\n"
            f"    try:\n        main({argv!r})\n    except SystemExit:\n        pass")
    assert _loaded_after(code) == []


def test_parser_choices_match_the_library() -> None:
    from s2r.sources import CONVENTIONS, EXPORT_FORMATS

    assert CONVENTION_CHOICES == CONVENTIONS and EXPORT_FORMAT_CHOICES == EXPORT_FORMATS


@pytest.mark.parametrize(("typo", "meant"), [
    ("realsense_d435_848x48", "realsense_d435_848x480"),
    ("realsens_d435_1280x720", "realsense_d435_1280x720"),
    ("Gazebo_Dual_Camera", "gazebo_dual_camera"),
    ("gazebo_dual_cam", "gazebo_dual_camera"),
    ("xbot", "xbot_u_stereo"),
])
def test_a_profile_typo_gets_did_you_mean(typo: str, meant: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "show", typo]) == 2
    err = capsys.readouterr().err
    assert f"did you mean '{meant}'" in err and err.count("\n") == 1


def test_a_file_name_typo_gets_did_you_mean(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "show", "realsense_d435_848x48.yaml"]) == 2
    assert "did you mean 'realsense_d435_848x480'" in capsys.readouterr().err


def test_no_close_name_lists_the_known_ones() -> None:
    text = did_you_mean("zzz", list_profiles())
    assert "did you mean" not in text and "realsense_d435_848x480" in text


_FAULT_PROBE = """
import resource, numpy as np
import s2r.cli  # noqa: F401 (the process-wide settings)
rng = np.random.default_rng(0)
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for n in rng.integers(1 << 15, 1 << 18, 400):  # arrays of 0.25-2 MB made and dropped, as the solves do
    x = np.ones(int(n)); y = np.ones(int(n) // 2); del x, y
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc malloc settings: Linux only")
def test_the_cli_keeps_freed_memory_for_reuse_unless_the_user_set_malloc() -> None:
    """``import s2r.cli`` sets glibc's mmap and trim thresholds: arrays of 0.25-2 MB made and dropped in a loop
    then reuse the heap instead of faulting fresh pages in each time (about 180 000 page faults against
    under 1 000 here); malloc settings the user made (``MALLOC_TRIM_THRESHOLD_``, or ``GLIBC_TUNABLES``) win."""
    import os

    def faults(**env: str) -> int:
        # without this process's malloc settings (a Dask nanny started by an earlier test sets MALLOC_TRIM_THRESHOLD_)
        clean = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_") and k != "GLIBC_TUNABLES"}
        out = subprocess.run([sys.executable, "-c", _FAULT_PROBE], capture_output=True, text=True, check=True,
                             env={**clean, **env}).stdout
        return int(out.strip().splitlines()[-1])

    tuned, default = faults(), faults(MALLOC_TRIM_THRESHOLD_=str(128 * 1024))  # glibc's own default
    assert tuned * 20 < default, (tuned, default)
    tunable = faults(GLIBC_TUNABLES="glibc.malloc.trim_threshold=131072:glibc.malloc.mmap_threshold=131072")
    assert tuned * 20 < tunable, (tuned, tunable)


_PLUGIN_PROBE = """
import os
import s2r.cli, s2r.profile
from pydantic.plugin import _loader
print(repr(os.environ.get("PYDANTIC_DISABLE_PLUGINS")), _loader._plugins is None)
"""


def test_the_cli_skips_pydantic_plugin_scan_unless_the_user_set_it() -> None:
    """``import s2r.cli`` sets ``PYDANTIC_DISABLE_PLUGINS=__all__``: building s2r's profile models then never
    walks every installed distribution's entry points (pydantic's plugin lookup, ~10 ms of start-up); a value
    the user set wins."""
    import os

    def probe(**env: str) -> list[str]:
        clean = {k: v for k, v in os.environ.items() if k != "PYDANTIC_DISABLE_PLUGINS"}
        out = subprocess.run([sys.executable, "-c", _PLUGIN_PROBE], capture_output=True, text=True, check=True,
                             env={**clean, **env}).stdout
        return out.split()

    assert probe() == ["'__all__'", "True"]
    assert probe(PYDANTIC_DISABLE_PLUGINS="") == ["''", "False"]  # the user's setting: plugins looked up


def test_validation_without_a_report_does_not_load_matplotlib() -> None:
    """The validation's own modules (and the command's module) leave matplotlib to the report writer: its
    0.3-0.6 s of import ran before the renders could start. The report still gets it."""
    probe = ("import sys\nimport s2r.validate, s2r.validate.run, s2r.validate.tasks, s2r.cli.validate_cmd\n"
             "before = 'matplotlib' in sys.modules\nfrom s2r.validate import write_validation_report\n"
             "print(before, 'matplotlib' in sys.modules, callable(write_validation_report))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "True", "True"]


def test_a_drift_check_loads_no_scipy_or_matplotlib() -> None:
    """``s2r check`` needs OpenCV (features, rectification) but neither SciPy (its rotations cost ~0.3 s of
    imports, a tenth of a check) nor Matplotlib (only for --report)."""
    loaded = _loaded_after("import s2r.cli.check_cmd, s2r.drift.check, s2r.drift.estimate, s2r.drift.source, "
                           "s2r.drift.swap, s2r.drift.verdict")
    assert "cv2" in loaded and "scipy" not in loaded and "matplotlib" not in loaded

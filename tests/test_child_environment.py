"""Programs s2r starts never look for shared libraries in the current folder.

``import cv2`` (opencv-python) sets LD_LIBRARY_PATH to ``<cv2>/../../lib64:`` when it was unset; the trailing
empty entry is the current folder to the dynamic loader, so every child would try ``./libpython3.11.so.1.0``
and the like first. The loader's own trace (LD_DEBUG=libs, written to files by LD_DEBUG_OUTPUT) is read here,
for the real children: the MuJoCo probe and a spawned Dask worker.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from s2r.executor import child_environment, children_search_no_relative_folder


@pytest.mark.parametrize(("value", "expected"), [
    ("/opt/cv2/../../lib64:", "/opt/cv2/../../lib64"),  # what import cv2 leaves
    (":", None), ("", None), ("lib:./x:/usr/local/lib::", "/usr/local/lib"),
    ("/a:/b", "/a:/b"),
    ("/opt/x;", "/opt/x"), ("/opt/x;rel:/b", "/opt/x:/b"),  # glibc splits at ';' too
    ("$ORIGIN/../lib:", "$ORIGIN/../lib"), ("${ORIGIN}/lib", "${ORIGIN}/lib"),  # the executable's folder
])
def test_child_environment_keeps_only_absolute_library_folders(value: str, expected: str | None) -> None:
    env = child_environment({"LD_LIBRARY_PATH": value, "HOME": "/h"})
    assert env.get("LD_LIBRARY_PATH") == expected and env["HOME"] == "/h"
    assert "LD_LIBRARY_PATH" not in child_environment({"PATH": "/bin"})


def test_children_search_no_relative_folder_restores_the_variable(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LD_LIBRARY_PATH", "/x/lib64:")
    with children_search_no_relative_folder():
        assert os.environ["LD_LIBRARY_PATH"] == "/x/lib64"
    assert os.environ["LD_LIBRARY_PATH"] == "/x/lib64:"
    monkeypatch.setenv("LD_LIBRARY_PATH", ":")
    with children_search_no_relative_folder():
        assert "LD_LIBRARY_PATH" not in os.environ
    assert os.environ["LD_LIBRARY_PATH"] == ":"


_RELATIVE_TRY = "trying file=libpython"  # the loader's line for a relative (current-folder) attempt


def _loader_trace(tmp_path: Path, args: list[str], *, processes: int = 2) -> str:
    """Run ``python args`` from ``tmp_path`` with the loader's library search of every process traced to files
    there (at least ``processes`` of them); all traces joined."""
    env = {**os.environ, "LD_DEBUG": "libs", "LD_DEBUG_OUTPUT": str(tmp_path / "ld")}
    env.pop("LD_LIBRARY_PATH", None)
    done = subprocess.run([sys.executable, *args], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=180)
    assert done.returncode == 0, done.stderr[-2000:]
    traces = sorted(tmp_path.glob("ld.*"))
    assert len(traces) >= processes, "the child processes left no loader trace"
    return "\n".join(p.read_text(errors="replace") for p in traces)


def _after_cv2(code: str) -> list[str]:
    """``python`` arguments running ``code`` in an interpreter that has imported cv2 (LD_LIBRARY_PATH ends ':')."""
    return ["-c", f"import cv2, os\nassert os.environ['LD_LIBRARY_PATH'].endswith(':')\n{code}"]


def test_a_plain_child_of_a_cv2_process_does_search_the_current_folder(tmp_path: Path) -> None:
    """The hazard itself, so the two checks below stay meaningful."""
    code = "import subprocess, sys\nsubprocess.run([sys.executable, '-c', 'pass'])"
    trace = _loader_trace(tmp_path, _after_cv2(code))
    assert _RELATIVE_TRY in trace


def test_the_mujoco_probe_does_not_search_the_current_folder(tmp_path: Path) -> None:
    pytest.importorskip("mujoco", reason="the mujoco extra is not installed")
    trace = _loader_trace(tmp_path, _after_cv2("from s2r.render._mujoco import _probe\n_probe('no-such-platform')"))
    assert _RELATIVE_TRY not in trace


_DASK_RUN = """
import cv2, os
from s2r.executor import open_runner


def library_path(_: int) -> str | None:
    return os.environ.get("LD_LIBRARY_PATH")


if __name__ == "__main__":
    assert os.environ["LD_LIBRARY_PATH"].endswith(":")
    with open_runner(workers=1, dask=True) as runner:
        seen = [o.result for o in runner.as_completed(library_path, [0])]
    assert seen and all(v is None or "" not in v.split(":") for v in seen), seen
    assert os.environ["LD_LIBRARY_PATH"].endswith(":")  # this process's own value is restored
"""


def test_a_spawned_dask_worker_does_not_search_the_current_folder(tmp_path: Path) -> None:
    pytest.importorskip("distributed", reason="Dask's distributed is not installed")
    script = tmp_path / "run.py"
    script.write_text(_DASK_RUN)
    assert _RELATIVE_TRY not in _loader_trace(tmp_path, [str(script)], processes=3)  # and a worker's trace

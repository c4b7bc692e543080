"""Programs s2r starts never look for shared libraries in the current folder.

An empty or relative LD_LIBRARY_PATH entry is the current folder to the dynamic loader, so every child would try
``./libpython3.11.so.1.0`` and the like first. opencv-python 5.0's ``import cv2`` left such an entry
(``<cv2>/../../lib64:``) when the variable was unset; 5.1 does not, but a user's shell or another library can.
These tests assert s2r's behaviour, not a dependency's: the hazard is planted in the environment the tests start
from, and cv2 is imported on top of it as s2r does. The loader's own trace (LD_DEBUG=libs, written to files by
LD_DEBUG_OUTPUT) is read for the real children: the MuJoCo probe and a spawned Dask worker.
"""

from __future__ import annotations

import json
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


#: The hazard, planted: an absolute folder that does not exist followed by an empty entry (the current folder).
_HAZARD = "/nonexistent-s2r-test/lib64:"


def _loader_trace(tmp_path: Path, args: list[str], *, processes: int = 2) -> str:
    """Run ``python args`` from ``tmp_path``, LD_LIBRARY_PATH set to the planted hazard, with the loader's library
    search of every process traced to files there (at least ``processes`` of them); the children's traces joined
    (the started process itself searches the current folder: it started on the hazard)."""
    env = {**os.environ, "LD_DEBUG": "libs", "LD_DEBUG_OUTPUT": str(tmp_path / "ld"), "LD_LIBRARY_PATH": _HAZARD}
    with subprocess.Popen([sys.executable, *args], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True) as run:
        _, stderr = run.communicate(timeout=180)
    assert run.returncode == 0, stderr[-2000:]
    traces = sorted(tmp_path.glob("ld.*"))
    assert len(traces) >= processes, "the child processes left no loader trace"
    children = [p for p in traces if p.name != f"ld.{run.pid}"]  # the test's own process started on the hazard
    assert len(children) == len(traces) - 1, "the started process left no trace of its own"
    return "\n".join(p.read_text(errors="replace") for p in children)


def _after_cv2(code: str) -> list[str]:
    """``python`` arguments running ``code`` in an interpreter that has imported cv2 on top of the planted hazard
    (whatever cv2 prepends, LD_LIBRARY_PATH still ends in an empty entry)."""
    return ["-c", f"import cv2, os\nassert os.environ['LD_LIBRARY_PATH'].endswith(':')\n{code}"]


def test_a_plain_child_of_a_cv2_process_does_search_the_current_folder(tmp_path: Path) -> None:
    """The planted hazard is real to the loader, so the two checks below stay meaningful."""
    code = "import subprocess, sys\nsubprocess.run([sys.executable, '-c', 'pass'])"
    trace = _loader_trace(tmp_path, _after_cv2(code))
    assert _RELATIVE_TRY in trace


def test_the_mujoco_probe_does_not_search_the_current_folder(tmp_path: Path) -> None:
    pytest.importorskip("mujoco", reason="the mujoco extra is not installed")
    probe = "from s2r.render.mujoco.backend import _probe\n_probe('no-such-platform')"
    trace = _loader_trace(tmp_path, _after_cv2(probe))
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


def test_what_this_cv2_leaves_is_cleaned_for_children() -> None:
    """Whatever ``import cv2`` leaves in a fresh interpreter (5.0: a trailing empty entry; 5.1: none), the child
    environment s2r builds from it holds no entry that depends on the current folder."""
    env = {k: v for k, v in os.environ.items() if k != "LD_LIBRARY_PATH"}
    code = ("import os, json, cv2\nfrom s2r.executor import child_environment\n"
            "print(json.dumps([os.environ.get('LD_LIBRARY_PATH'), child_environment().get('LD_LIBRARY_PATH')]))")
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    left_by_cv2, for_children = json.loads(done.stdout)
    if for_children is not None:
        entries = for_children.replace(";", ":").split(":")
        assert all(entry.startswith(("/", "$ORIGIN", "${ORIGIN}")) for entry in entries), for_children
    if left_by_cv2 is None or "" not in left_by_cv2.replace(";", ":").split(":"):
        pytest.skip(f"this cv2 {cv2_version()} leaves LD_LIBRARY_PATH={left_by_cv2!r}: no empty entry to clean "
                    "(the planted-hazard tests above still check the cleaning)")


def cv2_version() -> str:
    """The installed OpenCV's version, for the skip reason."""
    import cv2

    return str(cv2.__version__)

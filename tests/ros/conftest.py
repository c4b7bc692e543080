"""ROS 1 as Debian ships it, on a loopback-only roscore, for the tests marked ``ros`` (``make test-ros``).

The tests run in s2r's virtualenv and drive ROS through ``/usr/bin/python3 tests/ros/ros_helper.py`` (ROS's
Python modules live in the system interpreter). They skip with the reason when ROS is absent, and unless
selected with ``-m ros``, so ``make test`` stays quick and green on a machine without ROS.
"""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import time
import xmlrpc.client
from collections.abc import Iterator
from pathlib import Path

import pytest

SYSTEM_PYTHON = "/usr/bin/python3"
HELPER = Path(__file__).with_name("ros_helper.py")
#: What the tests need: ROS's tools and nodes, the nodelet plugin descriptions (-dev packages) and Python modules.
REQUIRED_FILES = ("/usr/bin/roscore", "/usr/lib/stereo_image_proc/stereo_image_proc",
                  "/usr/share/stereo_image_proc/nodelet_plugins.xml", "/usr/share/image_proc/nodelet_plugins.xml",
                  "/usr/share/nodelet/package.xml")
REQUIRED_MODULES = "rospy, rosbag, image_geometry, camera_calibration_parsers, stereo_msgs.msg, tf2_msgs.msg, cv2"


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if re.search(r"(?<![\w-])ros(?![\w-])", config.getoption("markexpr") or ""):
        return
    skip = pytest.mark.skip(reason="ROS consumer tests run with `make test-ros` (pytest -m ros)")
    for item in items:
        if item.get_closest_marker("ros") is not None:  # the marker, not a keyword: a test id [ros] is no ROS test
            item.add_marker(skip)


def _missing_ros() -> str | None:
    absent = [f for f in REQUIRED_FILES if not Path(f).exists()]
    if absent:
        return f"ROS 1 is not installed (missing {', '.join(absent)}; `make test-ros` installs it)"
    probe = subprocess.run([SYSTEM_PYTHON, "-c", f"import {REQUIRED_MODULES}"], capture_output=True, text=True,
                           check=False)
    if probe.returncode:
        return f"ROS 1 Python modules missing: {probe.stderr.strip().splitlines()[-1]} (`make test-ros` installs them)"
    return None


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@pytest.fixture(scope="session")
def ros_env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, str]]:
    """The environment of a running loopback-only roscore (ROS_MASTER_URI, ROS_IP, ROS_HOSTNAME, ROS_HOME)."""
    reason = _missing_ros()
    if reason:
        pytest.skip(reason)
    home = tmp_path_factory.mktemp("ros_home")
    port = _free_port()
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env.update(ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_IP="127.0.0.1", ROS_HOSTNAME="127.0.0.1",
               ROS_HOME=str(home), ROS_LOG_DIR=str(home / "log"), PYTHONPATH="")
    log = (home / "roscore.log").open("w")
    core = subprocess.Popen(["/usr/bin/roscore", "-p", str(port)], env=env, stdout=log, stderr=subprocess.STDOUT,
                            start_new_session=True)
    try:
        master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
        deadline = time.monotonic() + 60
        while True:
            try:
                if master.getSystemState("/s2r_tests")[0] == 1:
                    break
            except OSError:
                pass
            if time.monotonic() > deadline or core.poll() is not None:
                pytest.fail(f"roscore did not come up on port {port} (see {home / 'roscore.log'})")
            time.sleep(0.5)
        yield env
    finally:
        os.killpg(core.pid, signal.SIGTERM)  # roscore and the rosmaster/rosout it started, by our child's group
        try:
            core.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(core.pid, signal.SIGKILL)
            core.wait()
        log.close()


def run_helper(env: dict[str, str], *args: str, stdin: str | None = None, timeout: float = 120) -> str:
    """Run ros_helper.py with the system Python in ``env``; its stdout, or a test failure with its stderr."""
    done = subprocess.run([SYSTEM_PYTHON, str(HELPER), *args], env=env, input=stdin, capture_output=True, text=True,
                          timeout=timeout, check=False)
    if done.returncode:
        pytest.fail(f"ros_helper.py {args[0]} failed ({done.returncode}): {done.stderr.strip()[-2000:]}")
    return done.stdout

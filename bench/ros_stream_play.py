#!/usr/bin/python3
"""Driven by /usr/bin/python3 (Debian's ROS 1) from bench_stream.py; imports nothing of s2r.

    ros_stream_play.py BAG PARAMS.json

Starts a loopback-only roscore, the stereo_image_proc node in namespace /stereo with the disparity parameters of
PARAMS.json, subscribes to /stereo/disparity, plays BAG with ``rosbag play -r 1`` and prints JSON: disparities
received, wall seconds from the first to the last, pairs offered, and the node's CPU seconds meanwhile.
"""

import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
import xmlrpc.client

RATE = 1


def free_port():
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as handle:
        fields = handle.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def wait_master(uri, deadline):
    master = xmlrpc.client.ServerProxy(uri)
    while time.monotonic() < deadline:
        try:
            if master.getSystemState("/bench")[0] == 1:
                return master
        except OSError:
            pass
        time.sleep(0.3)
    sys.exit("roscore did not come up")


def main():
    bag, params_file = sys.argv[1], sys.argv[2]
    home = tempfile.mkdtemp(prefix="s2r-bench-ros-")
    port = free_port()
    os.environ.update(ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_IP="127.0.0.1", ROS_HOSTNAME="127.0.0.1",
                      ROS_HOME=home, ROS_LOG_DIR=os.path.join(home, "log"))
    core = subprocess.Popen(["/usr/bin/roscore", "-p", str(port)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    node = None
    try:
        master = wait_master(os.environ["ROS_MASTER_URI"], time.monotonic() + 60)
        import rospy
        from stereo_msgs.msg import DisparityImage

        with open(params_file) as handle:
            rospy.set_param("/stereo/stereo_image_proc", json.load(handle))
        node = subprocess.Popen(["/usr/lib/stereo_image_proc/stereo_image_proc"],
                                env=dict(os.environ, ROS_NAMESPACE="stereo"), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        got = []
        rospy.init_node("s2r_bench", anonymous=True, disable_signals=True)
        rospy.Subscriber("/stereo/disparity", DisparityImage, lambda m: got.append(time.monotonic()),
                         queue_size=100)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:  # the node subscribes to its inputs once someone wants its output
            subs = dict(master.getSystemState("/bench")[2][1])
            if "/stereo/left/image_raw" in subs:
                break
            time.sleep(0.3)
        cpu0 = cpu_seconds(node.pid)
        subprocess.run(["/usr/bin/rosbag", "play", "-q", "-r", str(RATE), "-d", "1", "--wait-for-subscribers",
                        bag], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(3.0)
        cpu = cpu_seconds(node.pid) - cpu0
        offered = int(subprocess.run(["/usr/bin/python3", "-c", "import rosbag,sys; b=rosbag.Bag(sys.argv[1]); "
                                      "print(b.get_message_count('/stereo/left/image_raw'))", bag],
                                     capture_output=True, text=True, check=True).stdout)
        wall = (got[-1] - got[0]) * len(got) / max(1, len(got) - 1) if len(got) > 1 else 0.0
        json.dump({"disparities": len(got), "wall_s": wall, "offered": offered, "rate": RATE, "node_cpu_s": cpu},
                  sys.stdout)
    finally:
        if node is not None:
            node.terminate()
            node.wait(timeout=10)
        os.killpg(core.pid, signal.SIGTERM)
        core.wait(timeout=20)


if __name__ == "__main__":
    main()

"""Throughput of ``s2r depth PROFILE --bag IN -o OUT --to ros1`` (the stream path) against a plain loop, and against
ROS's own stereo_image_proc playing the same bag.

Run: ``.venv/bin/python bench/bench_stream.py [--frames 60] [--rounds 3] [--no-ros]``

The input is one ROS 1 bag (written by rosbags): N grey 640x480 speckle pairs with their raw camera_info, for the
shipped ``gazebo_dual_camera`` profile, its own matcher with no post-processing (the settings stereo_image_proc is
given through the exported stereo_image_proc.yaml: the same disparities, bit for bit, REFERENCE.md).

- The plain anchor is a single-process Python loop doing the same work: read each pair from the same recording,
  ``StereoPipeline.compute`` (the same matcher settings), and the same bag writer, one frame after another.
- In-process: the stream path (``StereoPipeline.stream``: a decode thread, 2 matching threads, the bag written in
  the caller's thread) and the plain loop alternate, so load bursts hit both; medians of wall and CPU seconds.
- Whole process: ``s2r depth ...`` against ``python bench_stream.py --plain-child ...`` (imports included).
- stereo_image_proc (Debian's ROS 1, when installed; ``make test-ros`` installs it): ``rosbag play -r 1`` of the
  same bag into the stereo_image_proc node on a loopback roscore (the same disparity parameters), disparities
  counted by a subscriber: its frames per second (it drops what it cannot keep up with) against s2r's stream.

Load (``os.getloadavg``) is printed beside every figure: on 2 shared cores a busy neighbour halves any gain.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_depth import bench_profile, textured_pair

from s2r.depth.pipeline import StereoPipeline
from s2r.depth.stream import DepthFrame
from s2r.depth.writers import open_writer, write_stream
from s2r.formats.ros import ros_pair_from_profile
from s2r.profile import StereoProfile
from s2r.recordings import open_recording

LEFT, RIGHT = "/stereo/left/image_raw", "/stereo/right/image_raw"
HERE = Path(__file__).resolve().parent


def load() -> str:
    return "load " + " ".join(f"{v:.2f}" for v in os.getloadavg())


def stream_profile() -> StereoProfile:
    """The bench profile with speckle_range 31, the largest stereo_image_proc accepts (so both match alike)."""
    profile = bench_profile()
    return profile.model_copy(update={"matcher": profile.matcher.model_copy(update={"speckle_range": 31})})


def pipeline() -> StereoPipeline:
    return StereoPipeline(stream_profile(), preset="profile", postprocess=())


def write_input_bag(path: Path, frames: int) -> None:
    """N grey speckle pairs (mono8) and both raw camera_info at each stamp, as a ROS 1 bag (rosbags)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    t = store.types
    infos = ros_pair_from_profile(stream_profile())
    with Writer(path) as writer:
        conns = {topic: writer.add_connection(topic, kind, typestore=store) for topic, kind in (
            (LEFT, "sensor_msgs/msg/Image"), (RIGHT, "sensor_msgs/msg/Image"),
            ("/stereo/left/camera_info", "sensor_msgs/msg/CameraInfo"),
            ("/stereo/right/camera_info", "sensor_msgs/msg/CameraInfo"))}
        for k in range(frames):
            stamp = 1_700_000_000_000_000_000 + k * 33_333_333
            header = t["std_msgs/msg/Header"](seq=k, stamp=t["builtin_interfaces/msg/Time"](
                sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id=infos[0].frame_id or "left_optical")
            pair = [cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) for img in textured_pair(seed=k)]
            for topic, img, info in zip((LEFT, RIGHT), pair, infos, strict=True):
                msg = t["sensor_msgs/msg/Image"](header=header, height=img.shape[0], width=img.shape[1],
                                                 encoding="mono8", is_bigendian=0, step=img.shape[1],
                                                 data=np.ascontiguousarray(img).reshape(-1))
                writer.write(conns[topic], stamp, store.serialize_ros1(msg, "sensor_msgs/msg/Image"))
                side = "left" if topic == LEFT else "right"
                cam = t["sensor_msgs/msg/CameraInfo"](
                    header=header, height=info.height, width=info.width, distortion_model=info.distortion_model,
                    D=np.asarray(info.D, float), K=np.asarray(info.K, float).reshape(-1),
                    R=np.asarray(info.R, float).reshape(-1), P=np.asarray(info.P, float).reshape(-1), binning_x=0,
                    binning_y=0, roi=t["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0,
                                                                           width=0, do_rectify=False))
                writer.write(conns[f"/stereo/{side}/camera_info"], stamp,
                             store.serialize_ros1(cam, "sensor_msgs/msg/CameraInfo"))


def plain_loop(bag: Path, out: Path) -> int:
    """The anchor: one frame after another in this thread (read, compute, write), the same writer."""
    pipe = pipeline()
    source = open_recording(bag=bag, left_topic=LEFT, right_topic=RIGHT)
    count = 0
    with open_writer("ros1", out, pipe, force=True) as writer:
        for frame in source.frames():
            result = pipe.compute(frame.left, frame.right)
            writer.write(DepthFrame(index=frame.index, name=frame.name, source=frame.source,
                                    stamp_ns=frame.stamp_ns or 0, stamp_synthesized=False,
                                    frame_id=frame.frame_id or "left_optical", result=result))
            count += 1
        writer.publish()
    return count


def stream(bag: Path, out: Path) -> int:
    pipe = pipeline()
    source = open_recording(bag=bag, left_topic=LEFT, right_topic=RIGHT)
    with open_writer("ros1", out, pipe, force=True) as writer:
        count = write_stream(writer, pipe.stream(source, workers=2))
        writer.publish()
    return count


def match_only(bag: Path, _out: Path) -> int:
    """The stream without a writer: decode, rectify and match (stereo_image_proc's own share of the work)."""
    pipe = pipeline()
    return sum(1 for _ in pipe.stream(open_recording(bag=bag, left_topic=LEFT, right_topic=RIGHT), workers=2))


def timed(run: object, *args: Path) -> tuple[float, float, int]:
    cpu0, t0 = time.process_time(), time.perf_counter()
    n = run(*args)  # type: ignore[operator]
    return time.perf_counter() - t0, time.process_time() - cpu0, n


def in_process(bag: Path, tmp: Path, rounds: int) -> None:
    walls: dict[str, list[float]] = {"plain": [], "stream": []}
    cpus: dict[str, list[float]] = {"plain": [], "stream": []}
    n = 0
    for _ in range(rounds):
        for name, run in (("plain", plain_loop), ("stream", stream)):
            wall, cpu, n = timed(run, bag, tmp / f"{name}.bag")
            walls[name].append(wall)
            cpus[name].append(cpu)
    plain, fast = statistics.median(walls["plain"]), statistics.median(walls["stream"])
    print(f"in-process, {n} frames, median of {rounds}: plain loop {n / plain:5.1f} fps "
          f"({1e3 * statistics.median(cpus['plain']) / n:.1f} ms CPU/frame), stream {n / fast:5.1f} fps "
          f"({1e3 * statistics.median(cpus['stream']) / n:.1f} ms CPU/frame): x{plain / fast:.2f}  [{load()}]",
          flush=True)


def child(argv: list[str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def whole_process(bag: Path, tmp: Path, rounds: int, frames: int) -> None:
    s2r = str(Path(sys.executable).with_name("s2r"))
    profile = str(tmp / "profile.yaml")
    from s2r.formats.s2r_yaml import dump_profile

    dump_profile(stream_profile(), profile)
    cli = [s2r, "-q", "depth", profile, "--bag", str(bag), "--left-topic", LEFT, "--right-topic", RIGHT,
           "--postprocess", "", "-o", str(tmp / "cli.bag"), "--to", "ros1", "--force", "--keep-out-of-range"]
    plain = [sys.executable, __file__, "--plain-child", str(bag), str(tmp / "plain_child.bag")]
    res: dict[str, list[tuple[float, float]]] = {"plain": [], "cli": []}
    for _ in range(rounds):
        res["plain"].append(child(plain))
        res["cli"].append(child(cli))
    (pw, pc), (cw, cc) = ((statistics.median(w for w, _ in res[k]), statistics.median(c for _, c in res[k]))
                          for k in ("plain", "cli"))
    print(f"whole process, {frames} frames, median of {rounds}: plain loop script {pw:.2f} s ({pc:.2f} s CPU), "
          f"s2r depth --to ros1 {cw:.2f} s ({cc:.2f} s CPU): x{pw / cw:.2f}  [{load()}]", flush=True)


def ros_stereo_image_proc(bag: Path, tmp: Path) -> None:
    if not Path("/usr/lib/stereo_image_proc/stereo_image_proc").exists():
        print("stereo_image_proc: not installed (make test-ros installs Debian's ROS 1); skipped")
        return
    from s2r.depth.ros_params import ros_disparity_params

    params, notes = ros_disparity_params(pipeline().config)
    (tmp / "params.json").write_text(json.dumps(params))
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS", "PYTHON"))}
    fps: dict[str, list[float]] = {"bag": [], "match": []}

    def s2r_runs() -> None:  # s2r just before and just after ROS, so both see the same load
        for key, run in (("bag", stream), ("match", match_only)):
            wall, _, n = timed(run, bag, tmp / "ros_cmp.bag")
            fps[key].append(n / wall)

    s2r_runs()
    done = subprocess.run(["/usr/bin/python3", str(HERE / "ros_stream_play.py"), str(bag), str(tmp / "params.json")],
                          env=env, capture_output=True, text=True, timeout=600, check=False)
    s2r_runs()
    if done.returncode:
        print(f"stereo_image_proc: failed ({done.stderr.strip()[-300:]})")
        return
    got = json.loads(done.stdout)
    ros_fps = got["disparities"] / got["wall_s"] if got["wall_s"] > 0 else float("nan")
    node_ms = 1e3 * got["node_cpu_s"] / max(1, got["disparities"])
    to_bag, matching = statistics.mean(fps["bag"]), statistics.mean(fps["match"])
    print(f"stereo_image_proc (rosbag play -r {got['rate']}, {got['offered']} pairs offered): {got['disparities']} "
          f"disparities in {got['wall_s']:.2f} s = {ros_fps:.1f} fps, node CPU {node_ms:.1f} ms/frame; s2r right "
          f"before and after: stream into a bag {to_bag:.1f} fps (x{to_bag / ros_fps:.2f}), decode+match only "
          f"{matching:.1f} fps (x{matching / ros_fps:.2f} stereo_image_proc)  [{load()}]"
          + (f" (parameter notes: {'; '.join(notes)})" if notes else ""), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=90)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--no-ros", action="store_true")
    parser.add_argument("--plain-child", nargs=2, metavar=("BAG", "OUT"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.plain_child:
        plain_loop(Path(args.plain_child[0]), Path(args.plain_child[1]))
        return
    print(f"bench_stream: {os.cpu_count()} cores, {load()}, OpenCV threads {cv2.getNumThreads()}", flush=True)
    with tempfile.TemporaryDirectory() as name:
        tmp = Path(name)
        bag = tmp / "in.bag"
        write_input_bag(bag, args.frames)
        in_process(bag, tmp, args.rounds)
        whole_process(bag, tmp, args.rounds, args.frames)
        if not args.no_ros:
            ros_stereo_image_proc(bag, tmp)


if __name__ == "__main__":
    main()

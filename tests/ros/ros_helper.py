#!/usr/bin/python3
"""Driven by /usr/bin/python3 (Debian's ROS 1 Python) from tests/ros; imports nothing of s2r.

    ros_helper.py geometry FOLDER     (stdin JSON: "points_rect" [[x, y, z]], "raw_left" [[u, v]], "disparities")
    ros_helper.py stereo FOLDER LEFT RIGHT OUT [--timeout S]
    ros_helper.py bag OUT.bag LEFT_GLOB RIGHT_GLOB LEFT_TOPIC RIGHT_TOPIC
    ros_helper.py readbag BAG OUT       (rosbag's own reader: OUT/summary.json, OUT/depth_N.npy)
    ros_helper.py play BAG OUT NS       (rosbag play to rospy subscribers: the same files of what arrived)

``geometry`` reads FOLDER/left.yaml and right.yaml with camera_calibration_parsers and answers through
image_geometry (StereoCameraModel): rectified projections, rectifyPoint of raw left pixels, Z of disparities.
``stereo`` loads FOLDER/stereo_image_proc.yaml (when present) as the disparity node's parameters, starts
stereo_image_proc in namespace /stereo, publishes the raw grey pair with each camera_info (frame_id from the
file's s2r block) until a disparity arrives, and saves OUT/disparity.npy, OUT/rect_left.npy, OUT/rect_right.npy
and OUT/disparity.json. ``bag`` writes the image pairs (mono8) to a ROS 1 bag with rosbag.
"""

import argparse
import glob
import json
import os
import subprocess
import sys
import time

import camera_calibration_parsers
import cv2
import numpy as np
import rosbag
import rospy
import yaml
from image_geometry import StereoCameraModel
from sensor_msgs.msg import Image
from stereo_msgs.msg import DisparityImage

NODE = "/usr/lib/stereo_image_proc/stereo_image_proc"


def read_info(path):
    parsed = camera_calibration_parsers.readCalibration(path)
    if parsed is None:
        sys.exit(f"camera_calibration_parsers could not read {path}")
    with open(path, encoding="utf-8") as handle:
        block = (yaml.safe_load(handle) or {}).get("s2r") or {}
    info = parsed[1]
    info.header.frame_id = block.get("frame_id", "")
    return info


def geometry(folder):
    query = json.load(sys.stdin)
    model = StereoCameraModel()
    model.fromCameraInfo(read_info(os.path.join(folder, "left.yaml")), read_info(os.path.join(folder, "right.yaml")))
    pairs = [model.project3dToPixel(p) for p in query["points_rect"]]
    out = {"left": [list(a) for a, _ in pairs], "right": [list(b) for _, b in pairs],
           "rectified_left": [list(model.left.rectifyPoint(uv)) for uv in query["raw_left"]],
           "z": [model.getZ(d) for d in query["disparities"]], "baseline": 1.0 / model.Q[3, 2],
           "frame_ids": [model.left.tfFrame(), model.right.tfFrame()]}
    json.dump(out, sys.stdout)


def image_msg(image, stamp, frame_id):
    msg = Image()
    msg.header.stamp, msg.header.frame_id = stamp, frame_id
    msg.height, msg.width = image.shape
    msg.encoding, msg.is_bigendian, msg.step = "mono8", 0, image.shape[1]
    msg.data = np.ascontiguousarray(image).tobytes()
    return msg


def as_array(msg, dtype):
    return np.frombuffer(msg.data, dtype=dtype).reshape(msg.height, msg.width).copy()


def stereo(folder, left_png, right_png, out, timeout):
    params = os.path.join(folder, "stereo_image_proc.yaml")
    if os.path.exists(params):
        with open(params, encoding="utf-8") as handle:
            rospy.set_param("/stereo/stereo_image_proc", yaml.safe_load(handle))
    infos = [read_info(os.path.join(folder, f"{side}.yaml")) for side in ("left", "right")]
    images = [cv2.imread(p, cv2.IMREAD_GRAYSCALE) for p in (left_png, right_png)]
    env = dict(os.environ, ROS_NAMESPACE="stereo")
    node = subprocess.Popen([NODE], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    got = {}
    try:
        rospy.init_node("s2r_feeder", anonymous=True, disable_signals=True)
        pubs = {f"{side}/{kind}": rospy.Publisher(f"/stereo/{side}/{kind}", cls, queue_size=2)
                for side in ("left", "right") for kind, cls in (("image_raw", Image), ("camera_info", type(infos[0])))}
        rospy.Subscriber("/stereo/disparity", DisparityImage, lambda m: got.setdefault("disparity", m))
        rospy.Subscriber("/stereo/left/image_rect", Image, lambda m: got.setdefault("rect_left", m))
        rospy.Subscriber("/stereo/right/image_rect", Image, lambda m: got.setdefault("rect_right", m))
        deadline = time.monotonic() + timeout
        while len(got) < 3 and time.monotonic() < deadline:
            stamp = rospy.Time.now()
            for side, info, image in zip(("left", "right"), infos, images, strict=True):
                info.header.stamp = stamp
                pubs[f"{side}/camera_info"].publish(info)
                pubs[f"{side}/image_raw"].publish(image_msg(image, stamp, info.header.frame_id))
            time.sleep(0.3)
            if node.poll() is not None:
                sys.exit(f"stereo_image_proc exited with {node.returncode}")
    finally:
        node.terminate()
        node.wait(timeout=10)
    if len(got) < 3:
        sys.exit(f"no disparity from stereo_image_proc within {timeout} s (got {sorted(got)})")
    disp = got["disparity"]
    np.save(os.path.join(out, "disparity.npy"), as_array(disp.image, np.float32))
    np.save(os.path.join(out, "rect_left.npy"), as_array(got["rect_left"], np.uint8))
    np.save(os.path.join(out, "rect_right.npy"), as_array(got["rect_right"], np.uint8))
    with open(os.path.join(out, "disparity.json"), "w", encoding="utf-8") as handle:
        json.dump({"f": disp.f, "T": disp.T, "min_disparity": disp.min_disparity,
                   "max_disparity": disp.max_disparity, "frame_id": disp.header.frame_id}, handle)


def bag(out, left_glob, right_glob, left_topic, right_topic):
    lefts, rights = sorted(glob.glob(left_glob)), sorted(glob.glob(right_glob))
    with rosbag.Bag(out, "w") as writer:
        for k, (lp, rp) in enumerate(zip(lefts, rights, strict=True)):
            stamp = rospy.Time(1700000000 + k, 0)
            for topic, path in ((left_topic, lp), (right_topic, rp)):
                writer.write(topic, image_msg(cv2.imread(path, cv2.IMREAD_GRAYSCALE), stamp, "cam"), stamp)
    print(len(lefts))


def _depth_array(msg):
    dtype = np.float32 if msg.encoding == "32FC1" else np.uint16
    return as_array(msg, dtype)


def _summary(messages, out):
    """messages: [(topic, msg, bag time or None)] -> OUT/summary.json, OUT/depth_N.npy, OUT/disparity_N.npy."""
    summary = {"topics": {}, "depth_stamps": [], "frame_ids": [], "tf": [], "disparity": []}
    depth_n = disp_n = 0
    for topic, msg, _ in messages:
        summary["topics"][topic] = summary["topics"].get(topic, 0) + 1
        if msg._type == "tf2_msgs/TFMessage":
            summary["tf"] += [[t.header.frame_id, t.child_frame_id, t.transform.translation.x,
                               t.transform.translation.y, t.transform.translation.z] for t in msg.transforms]
            continue
        summary["frame_ids"].append(msg.header.frame_id)
        if topic.endswith("depth/image_rect"):
            summary["depth_stamps"].append(msg.header.stamp.to_nsec())
            np.save(os.path.join(out, f"depth_{depth_n}.npy"), _depth_array(msg))
            depth_n += 1
        elif msg._type == "stereo_msgs/DisparityImage":
            summary["disparity"].append([msg.f, msg.T, msg.min_disparity, msg.image.encoding])
            np.save(os.path.join(out, f"disparity_{disp_n}.npy"), as_array(msg.image, np.float32))
            disp_n += 1
    with open(os.path.join(out, "summary.json"), "w", encoding="utf-8") as handle:
        json.dump(summary, handle)


def readbag(path, out):
    with rosbag.Bag(path) as bag:
        info = bag.get_type_and_topic_info()
        types = {topic: value.msg_type for topic, value in info.topics.items()}
        messages = [(topic, msg, t.to_nsec()) for topic, msg, t in bag.read_messages()]
    _summary(messages, out)
    with open(os.path.join(out, "types.json"), "w", encoding="utf-8") as handle:
        json.dump(types, handle)


def play(path, out, namespace):
    import tf2_ros
    from stereo_msgs.msg import DisparityImage
    from tf2_msgs.msg import TFMessage

    got = []
    rospy.init_node("s2r_listener", anonymous=True, disable_signals=True)
    buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(buffer)  # tf's own listener: what RViz and every tf consumer uses
    for topic, cls in ((f"{namespace}/depth/image_rect", Image), (f"{namespace}/disparity", DisparityImage),
                       ("/tf_static", TFMessage)):
        rospy.Subscriber(topic, cls, lambda m, t=topic: got.append((t, m, None)), queue_size=1000)
    time.sleep(1.0)
    subprocess.run(["/usr/bin/rosbag", "play", "-q", "-d", "2", "-r", "0.5", path], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(2.0)
    _summary(got, out)
    depth = next(m for t, m, _ in got if t.endswith("depth/image_rect"))
    lookups = {}
    for t in got:
        if t[1]._type == "tf2_msgs/TFMessage":
            for tr in t[1].transforms:  # each child frame looked up in its parent, and the depth's in the parent
                found = buffer.lookup_transform(tr.header.frame_id, tr.child_frame_id, rospy.Time(0),
                                                rospy.Duration(5.0))
                r = found.transform.rotation
                lookups[tr.child_frame_id] = [found.header.frame_id, r.x, r.y, r.z, r.w]
    with open(os.path.join(out, "summary.json"), encoding="utf-8") as handle:
        summary = json.load(handle)
    summary["tf_lookups"] = lookups
    summary["depth_frame_known_to_tf"] = buffer.can_transform(
        lookups[depth.header.frame_id][0], depth.header.frame_id, rospy.Time(0), rospy.Duration(5.0))
    with open(os.path.join(out, "summary.json"), "w", encoding="utf-8") as handle:
        json.dump(summary, handle)


def main():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="cmd", required=True)
    sub.add_parser("geometry").add_argument("folder")
    p = sub.add_parser("stereo")
    for name in ("folder", "left", "right", "out"):
        p.add_argument(name)
    p.add_argument("--timeout", type=float, default=60.0)
    b = sub.add_parser("bag")
    for name in ("out", "left_glob", "right_glob", "left_topic", "right_topic"):
        b.add_argument(name)
    for name in ("readbag", "play"):
        r = sub.add_parser(name)
        r.add_argument("bag")
        r.add_argument("out")
        if name == "play":
            r.add_argument("namespace")
    args = parser.parse_args()
    if args.cmd == "readbag":
        readbag(args.bag, args.out)
        return
    if args.cmd == "play":
        play(args.bag, args.out, args.namespace)
        return
    if args.cmd == "geometry":
        geometry(args.folder)
    elif args.cmd == "stereo":
        stereo(args.folder, args.left, args.right, args.out, args.timeout)
    else:
        bag(args.out, args.left_glob, args.right_glob, args.left_topic, args.right_topic)


if __name__ == "__main__":
    main()

"""Image pairs from ROS bags: moved to :mod:`s2r.recordings.bags` (re-exported here for the old importers)."""

from s2r.recordings.bags import BagFrame, bag_image_topics, image_from_message, open_bag, paired_bag_frames

__all__ = ["BagFrame", "bag_image_topics", "image_from_message", "open_bag", "paired_bag_frames"]

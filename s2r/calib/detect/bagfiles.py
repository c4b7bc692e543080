"""The files of a ROS bag: moved to :mod:`s2r.recordings.bagfiles` (re-exported here for the old importers)."""

from s2r.recordings.bagfiles import bag_storage_files

__all__ = ["bag_storage_files"]

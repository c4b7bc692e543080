"""validate's per-profile tasks are queued longest first: depth before recovery, the larger profile first."""

from __future__ import annotations

from s2r.registry import load_profile
from s2r.validate.tasks import _longest_first


def test_larger_profile_first_within_each_kind() -> None:
    sim, real = load_profile("gazebo_dual_camera"), load_profile("realsense_d435_848x480")
    assert sim.left.width_px * sim.left.height_px < real.left.width_px * real.left.height_px
    order = _longest_first({"sim": sim, "real": real})
    assert order == [("depth", "real"), ("depth", "sim"), ("recovery", "real"), ("recovery", "sim")]


def test_equal_sizes_keep_the_roles_order() -> None:
    sim = load_profile("gazebo_dual_camera")
    assert _longest_first({"sim": sim, "real": sim}) == [("depth", "sim"), ("depth", "real"),
                                                         ("recovery", "sim"), ("recovery", "real")]
    assert _longest_first({"profile": sim}) == [("depth", "profile"), ("recovery", "profile")]

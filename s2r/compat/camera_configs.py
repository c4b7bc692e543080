"""The seed tutorial's ``camera_configs.py``, for whichever profile ``S2R_PROFILE`` names.

Code written against the tutorial (``import camera_configs``) runs unchanged on any profile with::

    from s2r.compat import camera_configs
    img1 = cv2.remap(frame1, camera_configs.left_map1, camera_configs.left_map2, cv2.INTER_LINEAR)
    threeD = cv2.reprojectImageTo3D(disparity, camera_configs.Q)

The profile is resolved ONCE, at import, from ``S2R_PROFILE`` (a profile name or YAML path). There is no
default on purpose: silently rectifying with the wrong camera gives plausible but wrong depth, so importing this
module without ``S2R_PROFILE`` raises :class:`s2r.errors.ProfileError` naming the variable. To switch profiles
in one process, use :func:`s2r.compat.camera_config_values` (or ``importlib.reload`` after changing the
variable).

Names (values as the seed's OpenCV calls make them, see :func:`s2r.compat.camera_config_values`):
left_camera_matrix, right_camera_matrix, left_distortion, right_distortion, R, T, size, R1, R2, P1, P2, Q,
left_map1, left_map2, right_map1, right_map2; also ``profile`` (the :class:`s2r.profile.StereoProfile`).
"""

from __future__ import annotations

import os
from typing import Any

from s2r.compat import camera_config_values
from s2r.errors import ProfileError
from s2r.registry import PROFILE_ENV

if not os.environ.get(PROFILE_ENV):
    raise ProfileError(
        "s2r.compat.camera_configs needs a profile", field=PROFILE_ENV,
        hint=f"set {PROFILE_ENV} to a profile name or YAML path, e.g. {PROFILE_ENV}=realsense_d435_848x480",
    )

_values: dict[str, Any] = camera_config_values(os.environ[PROFILE_ENV])
left_camera_matrix = _values["left_camera_matrix"]
right_camera_matrix = _values["right_camera_matrix"]
left_distortion = _values["left_distortion"]
right_distortion = _values["right_distortion"]
R = _values["R"]
T = _values["T"]
size = _values["size"]
R1 = _values["R1"]
R2 = _values["R2"]
P1 = _values["P1"]
P2 = _values["P2"]
Q = _values["Q"]
left_map1 = _values["left_map1"]
left_map2 = _values["left_map2"]
right_map1 = _values["right_map1"]
right_map2 = _values["right_map2"]
profile = _values["profile"]

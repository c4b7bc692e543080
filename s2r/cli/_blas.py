"""One BLAS thread for the command line, set before numpy loads (:mod:`s2r.cli` imports this module first).

s2r runs its parallel work in worker processes (``--jobs``); the matrices it multiplies are small (a joint
calibration's normal equations are about 22 x 4000), where OpenBLAS's extra threads mostly spin waiting for
work: about 8 % of a 40-pair calibration's CPU time on 2 cores, and they compete with the workers for the
cores. A value the user set (``OPENBLAS_NUM_THREADS``) is kept.
"""

from __future__ import annotations

import os

__all__: list[str] = []

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

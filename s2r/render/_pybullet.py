"""Import pybullet without its "pybullet build time" banner (written by C code to stderr at import).

The banner would precede every ``error: ...`` line of the CLI, so the import runs with file descriptor 2
pointed at /dev/null.
"""

from __future__ import annotations

import os
import sys
from typing import Any

__all__ = ["p"]


def _quiet_import() -> Any:
    sys.stderr.flush()
    saved = os.dup(2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 2)
        import pybullet

        return pybullet
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)


p: Any = _quiet_import()

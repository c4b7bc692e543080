"""Run the s2r CLI in a child process under the fuzz suite's bounds: a wall-clock timeout (a former hang must
answer within it), an address-space limit of 1 GB (a former unbounded read must fail inside it) and, for
full-disk cases, a file-size limit (RLIMIT_FSIZE: writes past it fail with EFBIG, as on a full disk; Python
ignores SIGXFSZ, so the write returns the error instead of killing the process). No root needed."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
from collections.abc import Callable

__all__ = ["MEMORY_LIMIT_BYTES", "TIMEOUT_S", "run_s2r"]

TIMEOUT_S = 20.0
MEMORY_LIMIT_BYTES = 1 << 30


def _limits(file_size: int | None, memory_bytes: int = MEMORY_LIMIT_BYTES) -> Callable[[], None]:
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))
        if file_size is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (file_size, file_size))
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    return apply


def run_s2r(*argv: str, file_size: int | None = None, cwd: str | None = None, timeout_s: float = TIMEOUT_S,
            memory_bytes: int = MEMORY_LIMIT_BYTES) -> subprocess.CompletedProcess[str]:
    """``python -m s2r ARGV`` under the bounds; raises ``subprocess.TimeoutExpired`` past ``timeout_s`` (a
    former hang; longer only for runs that do real work, such as a calibration on a loaded machine).
    ``memory_bytes``: a larger address-space cap for runs that load a GL stack (MuJoCo: EGL maps ~1 GB)."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, "-m", "s2r", *argv], capture_output=True, text=True, timeout=timeout_s,
                          check=False, env=env, cwd=cwd, preexec_fn=_limits(file_size, memory_bytes))

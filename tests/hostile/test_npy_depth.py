"""``.npy`` depth files are checked from their header before any allocation, and depth images must have the
profile's size (before: a 192-byte header declaring 200000x200000 gave exit 3, MemoryError for 298 GiB; a
sparse 6.4 GB file was read whole; 1x1, 20x30 and 0x848 arrays against an 848x480 profile gave exit 0 with
"Z accuracy 0.00 %, fill 100 %"). Each case runs in a child limited to 1 GB and 20 s."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.fileio import NotARegularFile, read_npy
from tests.hostile._limits import run_s2r

PROFILE = "realsense_d435_848x480"


def _header_only(path: Path, shape: tuple[int, ...], *, sparse_to: int = 0, descr: str = "<f4") -> Path:
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(buffer, {"descr": descr, "fortran_order": False, "shape": shape})
    with open(path, "wb") as handle:
        handle.write(buffer.getvalue())
        if sparse_to:
            handle.truncate(sparse_to)
    return path


def _quality(depth: Path) -> tuple[int, str]:
    done = run_s2r("depth-quality", PROFILE, "--depth", str(depth), "--wall", "--distance", "1.0")
    return done.returncode, done.stderr


@pytest.mark.parametrize("shape", [(200000, 200000), (40000, 40000)])
def test_huge_declared_shapes_are_refused_from_the_header(tmp_path: Path, shape: tuple[int, int]) -> None:
    path = _header_only(tmp_path / "d.npy", shape, sparse_to=6_400_000_128 if shape[0] == 40000 else 0)
    code, err = _quality(path)
    assert code == 2 and err.count("\n") == 1 and str(path) in err and "over the 256 MiB" in err


@pytest.mark.parametrize("shape", [(1, 1), (20, 30), (0, 848), (480, 848, 3)])
def test_depth_of_another_size_than_the_profile_is_refused(tmp_path: Path, shape: tuple[int, ...],
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "d.npy"
    np.save(path, np.ones(shape, np.float32))
    code = main(["depth-quality", PROFILE, "--depth", str(path), "--wall", "--distance", "1.0"])
    err = capsys.readouterr().err
    assert code == 2 and str(path) in err and err.count("\n") == 1, err
    assert "expects 848x480" in err or "single-channel" in err


def test_a_fifo_is_refused_at_once(tmp_path: Path) -> None:
    if not hasattr(os, "mkfifo"):
        pytest.skip("needs FIFOs (POSIX)")
    fifo = tmp_path / "d.npy"
    os.mkfifo(fifo)
    code, err = _quality(fifo)
    assert code == 2 and "not a regular file" in err
    with pytest.raises(NotARegularFile):
        read_npy(fifo)


def test_read_npy_refuses_what_numpy_would_allocate_or_unpickle(tmp_path: Path) -> None:
    good = tmp_path / "g.npy"
    np.save(good, np.arange(12, dtype=np.float64).reshape(3, 4).T)  # Fortran order survives
    assert read_npy(good).tolist() == np.arange(12, dtype=np.float64).reshape(3, 4).T.tolist()
    np.save(tmp_path / "o.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(ValueError, match="not plain numbers"):
        read_npy(tmp_path / "o.npy")
    with pytest.raises(ValueError, match="truncated"):
        read_npy(_header_only(tmp_path / "t.npy", (480, 848)))
    (tmp_path / "m.npy").write_bytes(b"not an npy file at all")
    with pytest.raises(ValueError):
        read_npy(tmp_path / "m.npy")

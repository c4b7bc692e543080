"""OpenCV FileStorage: YAML/XML round trips, the real stereo sample's intrinsics.yml, pairs, truncation."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.errors import FormatError
from s2r.formats.opencv import dump_opencv, load_opencv, opencv_to_text, read_opencv_stereo
from s2r.rectification import stereo_rectification
from tests.conftest import make_rig, shared_data
from tests.formats.rigs import assert_same_rig, distorted_rotated_rig, with_distortion


@pytest.mark.parametrize("suffix", [".yml", ".xml"])
def test_round_trip_yaml_and_xml(suffix: str, tmp_path: Path) -> None:
    rig = distorted_rotated_rig()
    out = dump_opencv(rig, tmp_path / f"stereo{suffix}")
    back = load_opencv(out)
    assert_same_rig(back, rig, tol=1e-12)
    assert back.provenance.method == "imported from OpenCV FileStorage"


@pytest.mark.parametrize(("model", "coeffs"), [
    ("rational_polynomial", (-0.1, 0.03, 0.001, 0.0005, 0.002, 0.01, -0.003, 0.001)),
    ("equidistant", (0.05, -0.01, 0.002, -0.0005)),
])
def test_round_trip_other_models(model: str, coeffs: tuple[float, ...], tmp_path: Path) -> None:
    rig = with_distortion(make_rig(rotation_deg=(0.1, 0.2, 0.3)), model, coeffs)
    assert_same_rig(load_opencv(dump_opencv(rig, tmp_path / "s.yml")), rig)


def test_written_nodes_are_opencvs_own(tmp_path: Path) -> None:
    rig = distorted_rotated_rig()
    out = dump_opencv(rig, tmp_path / "stereo.yml")
    storage = cv2.FileStorage(str(out), cv2.FILE_STORAGE_READ)
    np.testing.assert_array_equal(storage.getNode("M1").mat(), rig.left.K)
    np.testing.assert_array_equal(storage.getNode("T").mat().ravel(), rig.T)
    rect = stereo_rectification(rig)
    np.testing.assert_array_equal(storage.getNode("P2").mat(), rect.P2)
    np.testing.assert_array_equal(storage.getNode("Q").mat(), rect.Q)
    assert storage.getNode("image_width").real() == 640
    storage.release()
    assert "R1" not in opencv_to_text(rig, rectification=False)


def test_real_sample_intrinsics_yield_fx_534_803() -> None:
    path = shared_data("opencv_stereo_chessboard", "intrinsics.yml")
    data = read_opencv_stereo(path)
    assert data.M1[0, 0] == pytest.approx(534.803, abs=5e-4)
    assert data.M2[0, 0] == pytest.approx(534.803, abs=5e-4)
    assert data.R is None and data.T is None and data.image_size is None
    with pytest.raises(FormatError, match=r"intrinsics\.yml: R: not in the file: the extrinsics R and T .*extrinsics"):
        load_opencv(path, image_size=(640, 480))
    with pytest.raises(FormatError, match=r"the image size and the extrinsics .*--image-size.*extrinsics\.yml"):
        load_opencv(path)  # everything missing is said at once


def test_real_sample_intrinsics_with_an_extrinsics_file(tmp_path: Path) -> None:
    """intrinsics.yml + the sample's extrinsics.yml layout; T in squares scaled by the 25 mm square size."""
    intrinsics = shared_data("opencv_stereo_chessboard", "intrinsics.yml")
    extrinsics = tmp_path / "extrinsics.yml"
    storage = cv2.FileStorage(str(extrinsics), cv2.FILE_STORAGE_WRITE)
    storage.write("R", np.eye(3))
    storage.write("T", np.array([[-3.344], [0.042], [0.053]]))  # the README's figure, in squares
    storage.release()
    with pytest.raises(FormatError, match=r"image_width/image_height: not in the file: the image size.*--image-size"):
        load_opencv([intrinsics, extrinsics])
    rig = load_opencv([intrinsics, extrinsics], image_size=(640, 480), t_scale_m=0.025)
    assert rig.left.fx_px == pytest.approx(534.803, abs=5e-4) and rig.right.fx_px == pytest.approx(534.803, abs=5e-4)
    assert rig.baseline_m == pytest.approx(0.0836, abs=2e-4)  # |T| about 83.6 mm at 25 mm squares
    assert rig.left.D.tolist()[:2] == pytest.approx([0.29589439552724328, -1.0354662043042675])
    assert [s.path for s in rig.provenance.sources] == [str(intrinsics), str(extrinsics)]
    assert rig.provenance.notes == "T multiplied by 0.025 (metres per unit of the file's T)"


def test_truncated_files_give_one_line_errors(tmp_path: Path) -> None:
    full = dump_opencv(distorted_rotated_rig(), tmp_path / "full.yml").read_bytes()
    messages = set()
    for cut in range(10, len(full) - 40, 37):
        cut_file = tmp_path / "cut.yml"
        cut_file.write_bytes(full[:cut])
        with pytest.raises(FormatError) as info:
            load_opencv(cut_file)
        text = str(info.value)
        assert "\n" not in text and str(cut_file) in text
        messages.add(text.split(": ", 1)[1])
    assert any("truncated OpenCV FileStorage" in m for m in messages)


def test_bad_matrices_name_the_node(tmp_path: Path) -> None:
    rig = distorted_rotated_rig()
    text = opencv_to_text(rig, rectification=False)
    cases = {
        "nan": (text.replace("554.38271282264407", ".Nan", 1), "M1: must hold finite numbers only"),
        "count": (text.replace("cols: 5", "cols: 6", 1).replace("0.01 ]", "0.01, 0.2 ]", 1),
                  "D1: expected 4, 5 or 8 distortion coefficients, got 6"),
        "focal": (text.replace("554.38271282264407", "-554.0", 1), "M1: focal length must be positive"),
    }
    for label, (content, message) in cases.items():
        path = tmp_path / f"{label}.yml"
        path.write_text(content)
        with pytest.raises(FormatError, match=message):
            load_opencv(path)

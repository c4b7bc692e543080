"""One meaning of image noise (issue 38): ``render --noise N``, the sensor model's ``image_noise_dn`` and
``sensor fit`` are the same quantity, the sigma of additive noise in the GREY image the matcher and the fit read,
before 8-bit rounding. Rendered through PyBullet (its own blur and the 8-bit rounding), fitted back by the fit's
own image path (grey conversion, board detection, flat squares)."""

from __future__ import annotations

from pathlib import Path

import cv2
import pytest

from s2r.render.boards.sets import render_board_set
from s2r.sensor.fit.images import BoardImage, image_noise_dn
from s2r.sensor.fit.run import board_image, fit_images
from s2r.sensor.model import SensorModel
from tests.conftest import make_rig

RIG = make_rig(name="noise_rig", width=480, height=360, hfov_rad=1.0, baseline_m=0.06)


def _board_images(out: Path, *, noise: float = 0.0, sensor: SensorModel | None = None) -> list[BoardImage]:
    """The fit's board images of a 3-view rendered set (both cameras)."""
    board_set = render_board_set(RIG, out, views=3, seed=3, noise_sigma=noise, sensor=sensor, jobs=1)
    images = [board_image(p.name, cv2.imread(str(p), cv2.IMREAD_UNCHANGED), (9, 6))
              for p in board_set.left_paths + board_set.right_paths]
    found = [i for i in images if i is not None]
    assert len(found) >= 4
    return found


def _fitted(images: list[BoardImage]) -> tuple[float, float]:
    noise, blur, _ = fit_images(images)
    assert noise is not None and blur is not None
    return noise, blur


@pytest.mark.parametrize("noise", [1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
def test_render_noise_is_fitted_back(tmp_path: Path, noise: float) -> None:
    # the fit's noise measure itself; the margin it keeps from edges (3 blur sigmas + 2 px) uses PyBullet's
    # measured 0.29 px (the whole fit, edges included, is the slow test below)
    fitted, _ = image_noise_dn(_board_images(tmp_path / "set", noise=noise), blur_px=0.29)
    assert fitted == pytest.approx(noise, rel=0.10)


@pytest.mark.slow
def test_a_fitted_model_rendered_fits_back_to_itself(tmp_path: Path) -> None:
    noise, blur = _fitted(_board_images(tmp_path / "first", noise=2.5))
    assert noise == pytest.approx(2.5, rel=0.10)
    again, blur_again = _fitted(_board_images(tmp_path / "second", sensor=SensorModel(image_noise_dn=noise,
                                                                                      blur_sigma_px=blur)))
    assert again == pytest.approx(noise, rel=0.10)
    assert blur_again > blur  # the model's blur lands on top of the renderer's own

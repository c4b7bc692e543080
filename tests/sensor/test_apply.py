"""The sensor model applied: depth degradation's figures, seeding, render images, files and bad input."""

from __future__ import annotations

import numpy as np
import pytest

from s2r.cli import main
from s2r.render.rig import finish_image
from s2r.sensor import SensorModel, degrade_depth, load_sensor_model
from s2r.sensor.files import dump_sensor_model
from s2r.sensor.model import FillPoint
from tests.sensor.recordings import write_profile

MODEL = SensorModel(subpixel_sigma_px=0.1, subpixel_growth_px_per_m=0.05, edge_dropout_px=4.0, hole_scale_px=0.0,
                    fill_rate_by_distance=(FillPoint(distance_m=1.0, fill_rate_pct=90.0),
                                           FillPoint(distance_m=3.0, fill_rate_pct=50.0)))


def _step_scene() -> np.ndarray:
    z = np.full((200, 400), 2.0, np.float32)
    z[:, 200:] = 3.0
    return z


def test_depth_gets_the_models_noise_fill_and_band() -> None:
    out = degrade_depth(_step_scene(), MODEL, fb_px_m=20.0, rng=np.random.default_rng(0))
    valid = np.isfinite(out)
    assert valid[:, :190].mean() == pytest.approx(0.70, abs=0.01)  # fill 70 % at 2 m (linear 90 -> 50)
    assert valid[:, 210:].mean() == pytest.approx(0.50, abs=0.01)
    assert not valid[:, 198:202].any() and valid[:, 196].mean() > 0.6  # the 4 px band across the edge
    d = 20.0 / out[:, :190][valid[:, :190]]
    assert np.std(d - 10.0) == pytest.approx(0.15, rel=0.05)  # 0.1 + 0.05 * (2 - 1)


def test_depth_is_seeded_and_quantised() -> None:
    model = MODEL.model_copy(update={"disparity_step_px": 1 / 32})
    a = degrade_depth(_step_scene(), model, fb_px_m=20.0, rng=np.random.default_rng(5))
    b = degrade_depth(_step_scene(), model, fb_px_m=20.0, rng=np.random.default_rng(5))
    assert np.array_equal(a, b, equal_nan=True)
    d = 20.0 / a[np.isfinite(a)] * 32
    assert np.allclose(d, np.round(d), atol=1e-3)


def test_render_finish_applies_blur_then_grey_noise() -> None:
    rgb = np.full((64, 64, 3), 50, np.uint8)
    rgb[:, 32:] = 200
    model = SensorModel(image_noise_dn=3.0, blur_sigma_px=1.5)
    out = finish_image(rgb, gain=1.0, noise_sigma=0.0, rng=np.random.default_rng(0), sensor=model).astype(float)
    flat = out[:, 5:20, 0]
    assert flat.std() == pytest.approx(3.0, rel=0.1)
    assert np.array_equal(out[..., 0], out[..., 2])  # one grey noise plane on every channel
    profile = out[:, :, 1].mean(axis=0)
    assert 60 < profile[30] < 125 and 125 < profile[33] < 190  # a blurred step, not a sharp one


def test_sensor_yaml_round_trip_and_profile_section(tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = dump_sensor_model(MODEL, tmp_path / "sensor.yaml")
    assert load_sensor_model(path) == MODEL
    rig = write_profile(tmp_path / "rig.yaml")
    assert main(["sensor", "fit", "--profile", str(rig), "--left", str(tmp_path), "--pattern", "9x6", "--square",
                 "0.04", "-o", str(path)]) == 2  # exists: never overwritten without --force
    text = rig.read_text() + "sensor:\n  image_noise_dn: 2.0\n"
    rig.write_text(text)
    assert load_sensor_model(rig).image_noise_dn == 2.0


def test_apply_bad_input_is_one_line(tmp_path, capsys: pytest.CaptureFixture[str]) -> None:  # type: ignore[no-untyped-def]
    rig = write_profile(tmp_path / "rig.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("image_noise_dn: '3'\n")
    (tmp_path / "d").mkdir()
    np.save(tmp_path / "d" / "00.npy", np.full((240, 320), 1.0, np.float32))  # the rig's size
    assert main(["sensor", "apply", str(bad), str(tmp_path / "d"), "--profile", str(rig), "-o",
                 str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "bad.yaml: image_noise_dn" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
    good = dump_sensor_model(MODEL, tmp_path / "good.yaml")
    assert main(["sensor", "apply", str(good), str(tmp_path / "d"), "--profile", str(rig), "-o",
                 str(tmp_path / "out")]) == 0
    assert np.load(tmp_path / "out" / "00.npy").shape == (240, 320)
    assert main(["sensor", "apply", str(good), str(tmp_path / "d"), "--profile", str(rig), "-o",
                 str(tmp_path / "out")]) == 2  # the folder holds files: not overwritten


def test_export_gazebo_noise_comes_from_the_model(tmp_path) -> None:  # type: ignore[no-untyped-def]
    rig = write_profile(tmp_path / "rig.yaml")
    model = dump_sensor_model(SensorModel(image_noise_dn=2.55), tmp_path / "s.yaml")
    assert main(["profile", "export-gazebo", str(rig), "--sensor-model", str(model), "-o",
                 str(tmp_path / "cam.urdf")]) == 0
    text = (tmp_path / "cam.urdf").read_text()
    assert "<stddev>0.01</stddev>" in text

"""The profile model: validation messages, derived figures, YAML round trip, registry."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import s2r
from s2r.errors import OutputExistsError, ProfileError
from s2r.formats.s2r_yaml import dump_profile, load_profile_file, profile_to_yaml
from s2r.profile import StereoProfile
from tests.conftest import make_rig


def _mutated(profile: StereoProfile, path: str, value: object) -> dict:
    data = profile.model_dump(mode="json")
    node = data
    keys = path.split(".")
    for key in keys[:-1]:
        node = node[key]
    node[keys[-1]] = value
    return data


def test_derived_figures_match_hand_computation(rig: StereoProfile) -> None:
    fx = 640 / (2 * math.tan(1.047 / 2))
    assert rig.left.fx_px == pytest.approx(fx)
    assert rig.baseline_m == pytest.approx(0.1)
    np.testing.assert_allclose(rig.T, [-0.1, 0.0, 0.0], atol=1e-15)
    assert rig.left.K[0, 2] == 319.5 and rig.left.K[1, 2] == 239.5
    assert rig.image_size == (640, 480)
    assert math.degrees(rig.left.hfov_rad) == pytest.approx(math.degrees(1.047), abs=1e-9)
    # Intel's model RMS = Z^2 s / (fx B): at 2 m, 4 * 0.08 / (554.26 * 0.1)
    assert float(rig.depth_rms_m(2.0)) == pytest.approx(4 * 0.08 / (fx * 0.1))
    assert rig.max_depth_within_m(0.02) == pytest.approx(0.02 * fx * 0.1 / 0.08)
    # num disparities to see 0.3 m: fx B / z = 184.75 -> 192
    assert rig.num_disparities_for(0.3) == 192
    near, far = rig.depth_range_m(rig.matcher.model_copy(update={"num_disparities": 64}))
    assert near == pytest.approx(fx * 0.1 / 63) and far == pytest.approx(fx * 0.1)


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        ("left.fx_px", -5.0, "left.fx_px"),
        ("left.fy_px", 0.0, "left.fy_px"),
        ("right.cx_px", 900.0, "right"),
        ("left.distortion.coefficients", [0.1, 0.2], "left.distortion"),
        ("extrinsics.rotation", [[1, 0, 0], [0, 1, 0], [0, 0.1, 1]], "extrinsics"),
        ("extrinsics.rotation", [[1, 0, 0], [0, 1, 0], [0, 0, -1]], "extrinsics"),
        ("extrinsics.translation_m", [0.0, 0.0, 0.0], "extrinsics"),
        ("left.fx_px", float("nan"), "left.fx_px"),
        ("left.cy_px", float("inf"), "left.cy_px"),
        ("left.unknown_key", 1, "left.unknown_key"),
        ("right.width_px", 1280, "(top level)"),
    ],
)
def test_invalid_profiles_name_the_field(rig: StereoProfile, tmp_path: Path, path: str, value: object,
                                         field: str) -> None:
    import yaml

    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(_mutated(rig, path, value)))
    with pytest.raises(ProfileError) as info:
        load_profile_file(bad)
    message = str(info.value)
    assert str(bad) in message and field in message and "\n" not in message


def test_yaml_round_trip_is_exact(distorted_rig: StereoProfile, tmp_path: Path) -> None:
    out = dump_profile(distorted_rig, tmp_path / "p.yaml")
    back = load_profile_file(out)
    assert back == distorted_rig
    np.testing.assert_array_equal(back.R, distorted_rig.R)
    assert "fx_px" in profile_to_yaml(back)


def test_dump_refuses_to_overwrite_without_force(rig: StereoProfile, tmp_path: Path) -> None:
    out = dump_profile(rig, tmp_path / "p.yaml")
    before = out.read_text()
    with pytest.raises(OutputExistsError):
        dump_profile(make_rig(baseline_m=0.2), out)
    assert out.read_text() == before
    dump_profile(make_rig(baseline_m=0.2), out, force=True)
    assert load_profile_file(out).baseline_m == pytest.approx(0.2)


def test_malformed_and_missing_files(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("left: [unclosed\n")
    with pytest.raises(ProfileError, match="malformed YAML"):
        load_profile_file(bad)
    with pytest.raises(ProfileError, match="file not found"):
        load_profile_file(tmp_path / "nope.yaml")


def test_registry_finds_shipped_and_user_profiles(rig: StereoProfile, tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    profile = s2r.load_profile("realsense_d435_848x480")
    assert profile.provenance.origin == "nominal"
    assert profile.baseline_m == pytest.approx(0.05)
    assert profile.left.K.shape == (3, 3) and profile.right.D.shape == (5,)
    dump_profile(rig, tmp_path / "my_rig.yaml")
    monkeypatch.setenv("S2R_PROFILE_PATH", str(tmp_path))
    assert s2r.load_profile("my_rig") == rig
    monkeypatch.setenv("S2R_PROFILE", "my_rig")
    assert s2r.load_profile() == rig
    with pytest.raises(ProfileError, match="realsense_d435_848x480"):
        s2r.load_profile("no_such_profile")


def test_shipped_realsense_figures_follow_reference() -> None:
    p = s2r.load_profile("realsense_d435_848x480")
    assert 421 <= p.left.fx_px <= 427 and 420 <= p.left.cx_px <= 425 and 234 <= p.left.cy_px <= 236
    # REFERENCE: about 3.8 mm at 1 m and 15 mm at 2 m at 848x480
    assert float(p.depth_rms_m(1.0)) == pytest.approx(0.0038, abs=0.0002)
    assert float(p.depth_rms_m(2.0)) == pytest.approx(0.015, abs=0.0006)
    hd = s2r.load_profile("realsense_d435_1280x720")
    assert 636 <= hd.left.fx_px <= 645 and 634 <= hd.left.cx_px <= 642


def test_atomic_writes_get_ordinary_permissions(rig: StereoProfile, tmp_path: Path) -> None:
    import os

    out = dump_profile(rig, tmp_path / "p.yaml")
    umask = os.umask(0)
    os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


def test_profile_yaml_from_libyaml_matches_pure_python_and_loads_back(rig: StereoProfile, tmp_path: Path) -> None:
    """Profiles are written by libyaml's emitter where PyYAML has it (faster). Its text equals the pure-Python
    emitter's for every shipped profile; for odd names and long non-ASCII source paths (which libyaml keeps on
    one line where pure Python folds them) the file loads back to the same profile."""
    import yaml

    from s2r.formats import s2r_yaml
    from s2r.profile import SourceFile
    from s2r.registry import list_profiles, load_profile

    class PurePython(yaml.SafeDumper):
        pass

    PurePython.add_representer(list, s2r_yaml._represent_list)
    assert yaml.__with_libyaml__ and issubclass(s2r_yaml._FlowListDumper, yaml.CSafeDumper)
    for profile in (load_profile(name) for name in list_profiles()):
        data = profile.model_dump(mode="json", exclude_none=True)
        assert profile_to_yaml(profile).endswith(yaml.dump(data, Dumper=PurePython, sort_keys=False, width=110))
    path = "/data/калибровка_стереокамеры/" + "снимки_" * 12 + "/left/0001.png"
    odd = [rig.model_copy(update={"name": name}) for name in ("a\u2028b\x85c", "x: y # 'z'", "ünï ☃\ttab", "w " * 80)]
    odd.append(rig.model_copy(update={"provenance": rig.provenance.model_copy(
        update={"sources": (SourceFile(path=path, sha256="0" * 64),)})}))
    for k, profile in enumerate(odd):
        out = tmp_path / f"odd{k}.yaml"
        out.write_text(profile_to_yaml(profile), encoding="utf-8")
        assert yaml.safe_load(out.read_text(encoding="utf-8")) == profile.model_dump(mode="json", exclude_none=True)

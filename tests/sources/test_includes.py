"""SDF includes: one resolver confined to the description's folder and the model folders, with a depth, file and byte
budget over the whole expansion (issue 23 items 6-8), and includes that name nothing here (issue 24 item 3)."""

from __future__ import annotations

import math
import resource
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import SourceError
from s2r.registry import load_profile
from s2r.sources import load_description_profile
from s2r.sources.includes import IncludeBudget, MissingInclude, model_name, resolve
from s2r.sources.sdf.include import MODEL_PATH_ENVS

FIXTURES = Path(__file__).parent / "fixtures"
CAMERA_LINK = """<link name="link">
  <sensor name="left" type="camera"><pose>0 0.035 0 0 0 0</pose>
    <camera><horizontal_fov>1.2</horizontal_fov><image><width>640</width><height>480</height></image></camera>
  </sensor>
  <sensor name="right" type="camera"><pose>0 -0.035 0 0 0 0</pose>
    <camera><horizontal_fov>1.2</horizontal_fov><image><width>640</width><height>480</height></image></camera>
  </sensor>
</link>"""


@pytest.fixture(autouse=True)
def _no_model_path(monkeypatch: pytest.MonkeyPatch) -> None:
    for env in MODEL_PATH_ENVS:
        monkeypatch.delenv(env, raising=False)


def _world(folder: Path, uri: str, *, name: str = "world.sdf", body: str = "") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(f'<sdf version="1.9"><world name="w"><include><uri>{uri}</uri></include>{body}</world></sdf>\n')
    return path


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out + err


def test_self_including_sdf_is_named_not_a_recursion_error(tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    world = tmp_path / "self.sdf"
    world.write_text('<sdf version="1.9"><model name="m"><include><uri>self.sdf</uri></include></model></sdf>\n')
    with pytest.raises(SourceError, match=r"self\.sdf includes itself"):
        load_description_profile(world)
    code, text = _cli(["profile", "from-urdf", str(world), "-o", str(tmp_path / "p.yaml")], capsys)
    assert code == 2 and text.count("\n") == 1 and "includes itself" in text and "<include> line 1" in text


def test_a_cycle_through_two_files_and_a_deep_chain_stop(tmp_path: Path) -> None:
    (tmp_path / "a.sdf").write_text('<sdf><model name="a"><include><uri>b.sdf</uri></include></model></sdf>')
    (tmp_path / "b.sdf").write_text('<sdf><model name="b"><include><uri>a.sdf</uri></include></model></sdf>')
    with pytest.raises(SourceError, match=r"a\.sdf includes itself \(through a\.sdf -> b\.sdf\)"):
        load_description_profile(tmp_path / "a.sdf")
    for level in range(12):  # a chain of 12 distinct files: deeper than the 8 levels allowed
        (tmp_path / f"c{level}.sdf").write_text(
            f'<sdf><model name="c{level}"><include><uri>c{level + 1}.sdf</uri></include></model></sdf>')
    with pytest.raises(SourceError, match="includes nested more than 8 deep"):
        load_description_profile(tmp_path / "c0.sdf")


def test_include_fan_out_stops_on_the_file_budget(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The reproducer: 7 files under 400 bytes, each including the next 12 times (12^7 = 35 million files)."""
    for level in range(7):
        inner = "".join(f"<include><uri>f{level + 1}.sdf</uri><name>m{i}</name></include>" for i in range(12))
        body = inner if level < 6 else '<link name="l"/>'
        (tmp_path / f"f{level}.sdf").write_text(f'<sdf><model name="f{level}">{body}</model></sdf>')
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    code, text = _cli(["profile", "from-urdf", str(tmp_path / "f0.sdf"), "-o", str(tmp_path / "p.yaml")], capsys)
    assert code == 2 and text.count("\n") == 1, text
    assert "more than 256 included files" in text
    assert not (tmp_path / "p.yaml").exists()
    after = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    assert max(before, after) < (1 << 30) // 1024  # kB: the expanding child stayed far under 1 GB


@pytest.mark.parametrize("uri", ["model://../../secret/cam.sdf", "model://../secret", "model://./x"])
def test_model_uri_with_dot_dot_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], uri: str) -> None:
    secret = tmp_path / "secret"
    secret.mkdir()
    (secret / "cam.sdf").write_text(f'<sdf><model name="cam">{CAMERA_LINK}</model></sdf>')
    world = _world(tmp_path / "desc" / "worlds", uri)
    models = tmp_path / "desc" / "models"
    models.mkdir()
    code, text = _cli(["profile", "from-urdf", str(world), "--package-path", str(models), "-o",
                       str(tmp_path / "p.yaml")], capsys)
    assert code == 2 and "refused" in text and text.count("\n") == 1, text
    assert not (tmp_path / "p.yaml").exists()


def test_absolute_and_file_uris_outside_answer_the_same_whether_or_not_the_file_exists(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "exists.sdf").write_text("not xml at all")
    messages = []
    for uri in (f"{outside}/exists.sdf", f"{outside}/missing.sdf", f"file://{outside}/exists.sdf",
                f"file://{outside}/missing.sdf", "/etc/passwd", "../outside/exists.sdf", "/nonexistent/dir/x.sdf"):
        world = _world(tmp_path / "desc", uri)
        code, text = _cli(["lint", str(world)], capsys)
        assert code == 2 and text.count("\n") == 1, text
        messages.append(text.replace(uri, "URI").replace(repr(uri), "URI"))
        assert "malformed" not in text and "not found" not in text
    assert "points outside the description's folder and the model folders: refused" in messages[0]
    assert len({m.split("include ")[0] for m in messages}) == 1


def test_symlink_out_of_the_description_folder_is_refused(tmp_path: Path) -> None:
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "cam.sdf").write_text(f'<sdf><model name="cam">{CAMERA_LINK}</model></sdf>')
    desc = tmp_path / "desc"
    desc.mkdir()
    (desc / "cam.sdf").symlink_to(outside / "cam.sdf")
    with pytest.raises(SourceError, match="points outside"):
        load_description_profile(_world(desc, "cam.sdf"))


def test_provenance_lists_every_included_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    world = FIXTURES / "gz_world_with_include.sdf"
    out = tmp_path / "p.yaml"
    code, text = _cli(["profile", "from-urdf", str(world), "--package-path", str(FIXTURES / "models"), "-o",
                       str(out)], capsys)
    assert code == 0, text
    sources = [Path(s.path).name for s in load_profile(out).provenance.sources]
    assert sources == ["gz_world_with_include.sdf", "model.config", "stereo.sdf"]


def test_resolve_is_confined_and_budget_counts_across_calls(tmp_path: Path) -> None:
    root = tmp_path / "root"
    (root / "sub").mkdir(parents=True)
    (root / "sub" / "a.xml").write_text("<mujoco/>")
    including = root / "main.xml"
    assert resolve("sub/a.xml", including_file=including, roots=[root]) == (root / "sub" / "a.xml").resolve()
    with pytest.raises(SourceError, match="points outside"):
        resolve("../root2/a.xml", including_file=including, roots=[root])
    with pytest.raises(MissingInclude, match="not found"):
        resolve("sub/b.xml", including_file=including, roots=[root])
    budget = IncludeBudget(max_depth=2, max_files=3, max_bytes=20)
    target = root / "sub" / "a.xml"
    with budget.nested(target, including_file=including, field="<include>"):
        assert budget.read(target, including_file=including, field="<include>") == "<mujoco/>"
        with pytest.raises(SourceError, match="includes itself"), \
                budget.nested(target, including_file=including, field="<include>"):
            pass
    budget.read(target, including_file=including, field="<include>")
    with pytest.raises(SourceError, match="over the 0 MiB"):  # 18 of 20 bytes spent: the next 9 do not fit
        budget.read(target, including_file=including, field="<include>")
    with pytest.raises(SourceError, match="more than 3 included files"):
        budget.read(target, including_file=including, field="<include>")
    assert budget.included == [target]


def test_model_names_of_standard_uris() -> None:
    assert model_name("model://sun") == "sun"
    assert model_name("https://fuel.gazebosim.org/1.0/OpenRobotics/models/Ground Plane/2") == "ground_plane"
    assert model_name("https://fuel.gazebosim.org/1.0/OpenRobotics/models/Ground%20Plane") == "ground_plane"
    assert model_name("cam.sdf") == ""


def test_world_with_standard_includes_and_inline_cameras(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 24 item 3: model://sun and a Fuel ground plane are skipped with a note; the cameras are inline."""
    out = tmp_path / "p.yaml"
    code, text = _cli(["profile", "from-urdf", str(FIXTURES / "world_inline_cameras.world"), "-o", str(out)], capsys)
    assert code == 0, text
    assert "skipped <include> model://sun (<include> line 8)" in text and "Ground Plane" in text
    profile = load_profile(out)
    assert profile.left.fx_px == pytest.approx(320 / math.tan(1.047 / 2), abs=1e-9)
    assert pytest.approx([-0.1, 0.0, 0.0], abs=1e-12) == profile.T
    assert "skipped <include> model://sun" in profile.provenance.notes
    assert "skipped <include> https://fuel.gazebosim.org" in profile.provenance.notes


def test_missing_include_that_might_hold_a_camera_still_errors(tmp_path: Path) -> None:
    world_text = (FIXTURES / "world_inline_cameras.world").read_text().replace("model://sun", "model://mystery_rig")
    world = tmp_path / "w.world"
    world.write_text(world_text)
    profile = load_description_profile(world)  # the file's own two cameras are the pair: said in a note
    assert "skipped <include> model://mystery_rig (<include> line 8): not available here, the file defines a " \
           "stereo pair itself" in profile.provenance.notes
    profile = load_description_profile(world, left="left_camera", right="right_camera")  # asked for inline ones
    assert "skipped <include> model://mystery_rig" in profile.provenance.notes
    with pytest.raises(SourceError, match="mystery_rig"):
        load_description_profile(world, left="left_camera", right="front_right")
    one = world_text.replace('<sensor name="right_camera" type="camera">', '<sensor name="r" type="imu">')
    world.write_text(one)  # one camera inline: the other may be in the missing model
    with pytest.raises(SourceError, match=r"<include> line 8: model 'mystery_rig' .* not found"):
        load_description_profile(world)


def test_a_failed_command_prints_only_its_error_not_the_skip_notes(tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    world = tmp_path / "far.world"
    world.write_text((FIXTURES / "world_inline_cameras.world").read_text().replace("0 -0.05 0 0 0 0", "0 -20 0 0 0 0"))
    code, text = _cli(["profile", "from-urdf", str(world), "-o", str(tmp_path / "p.yaml")], capsys)
    assert code == 2 and text.count("\n") == 1 and text.startswith("error: ") and "skipped" not in text


def test_random_include_graphs_answer_with_a_profile_or_one_error(tmp_path: Path) -> None:
    """Seeded fuzz: files including each other, themselves, missing files, folders outside and model:// names with
    '..' answer with a profile or one SourceError, never read outside the roots, within the budget."""
    import random

    rng = random.Random(23)
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "cam.sdf").write_text(f'<sdf><model name="cam">{CAMERA_LINK}</model></sdf>')
    uris = ["f{}.sdf", "../outside/cam.sdf", f"{outside}/cam.sdf", f"file://{outside}/cam.sdf", "model://../outside",
            "model://cams", "model://sun", "https://fuel.gazebosim.org/1.0/x/models/y", "missing.sdf", "f{}.sdf"]
    for case in range(12):
        desc = tmp_path / f"case{case}"
        (desc / "models" / "cams").mkdir(parents=True)
        (desc / "models" / "cams" / "model.sdf").write_text(f'<sdf><model name="cams">{CAMERA_LINK}</model></sdf>')
        for index in range(5):
            picks = [rng.choice(uris).format(rng.randrange(5)) for _ in range(rng.randrange(4))]
            body = "".join(f"<include><uri>{u}</uri><name>i{n}</name></include>" for n, u in enumerate(picks))
            (desc / f"f{index}.sdf").write_text(f'<sdf><model name="f{index}">{body}</model></sdf>')
        try:
            profile = load_description_profile(desc / "f0.sdf", package_paths=[desc / "models"])
        except SourceError as exc:
            assert "\n" not in str(exc) and "Traceback" not in str(exc)
            continue
        assert all(str(outside) not in s.path for s in profile.provenance.sources)


def test_models_nested_thousands_deep_are_one_error_not_a_recursion_error(tmp_path: Path,
                                                                          capsys: pytest.CaptureFixture[str]) -> None:
    deep = tmp_path / "deep.sdf"
    deep.write_text("<sdf>" + '<model name="m">' * 5000 + "</model>" * 5000 + "</sdf>")
    code, text = _cli(["lint", str(deep)], capsys)
    assert code == 2 and text.count("\n") == 1 and "models nested more than 64 deep" in text


def test_a_large_included_file_and_many_elements_stop_on_the_budget(tmp_path: Path) -> None:
    (tmp_path / "big.sdf").write_text('<sdf><model name="big">' + "<a/>" * 600_000 + "</model></sdf>")
    with pytest.raises(SourceError, match=r"included file 'big\.sdf': \d+ bytes, over the 2 MiB"):
        load_description_profile(_world(tmp_path, "big.sdf"))
    (tmp_path / "many.sdf").write_text('<sdf><model name="many">' + "<a/>" * 60_000 + "</model></sdf>")
    world = tmp_path / "two.sdf"
    world.write_text('<sdf><world name="w"><include><uri>many.sdf</uri><name>a</name></include>'
                     '<include><uri>many.sdf</uri><name>b</name></include></world></sdf>')
    with pytest.raises(SourceError, match="the included files hold more than 100000 XML elements"):
        load_description_profile(world)


def test_a_world_may_include_from_its_own_ros_package(tmp_path: Path) -> None:
    """worlds/ and models/ side by side in one ROS package (package.xml above): allowed, as for xacro; the folder
    above the package is not."""
    package = tmp_path / "my_gazebo"
    (package / "models" / "cam").mkdir(parents=True)
    (package / "package.xml").write_text("<package><name>my_gazebo</name></package>")
    (package / "models" / "cam" / "model.sdf").write_text(f'<sdf><model name="cam">{CAMERA_LINK}</model></sdf>')
    world = _world(package / "worlds", "../models/cam")
    assert load_description_profile(world).baseline_m == pytest.approx(0.07, abs=1e-12)
    (tmp_path / "cam.sdf").write_text(f'<sdf><model name="cam">{CAMERA_LINK}</model></sdf>')
    with pytest.raises(SourceError, match="points outside"):
        load_description_profile(_world(package / "worlds", "../../cam.sdf", name="up.sdf"))


def test_an_installed_sun_model_is_a_light_and_is_left_out(tmp_path: Path) -> None:
    """With Gazebo's model folder on the path, model://sun resolves to an SDF holding a <light>, not a <model>."""
    sun = tmp_path / "models" / "sun"
    sun.mkdir(parents=True)
    (sun / "model.config").write_text("<model><name>Sun</name><sdf version='1.6'>model.sdf</sdf></model>")
    (sun / "model.sdf").write_text('<sdf version="1.6"><light type="directional" name="sun"/></sdf>')
    profile = load_description_profile(FIXTURES / "world_inline_cameras.world", package_paths=[tmp_path / "models"])
    assert profile.baseline_m == pytest.approx(0.1, abs=1e-12)
    assert [Path(s.path).name for s in profile.provenance.sources][1:] == ["model.config", "model.sdf"]

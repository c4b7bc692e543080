"""The repository itself: no tracked link leaves it, and the lock pins every declared dependency."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
import tomllib

ROOT = Path(__file__).resolve().parents[1]


def _tracked_links() -> list[tuple[str, str]]:
    """(path, target) of every symbolic link git tracks (mode 120000)."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    listing = subprocess.run(["git", "ls-files", "-s"], cwd=ROOT, capture_output=True, text=True, check=True)
    links = [line.split("\t", 1)[1] for line in listing.stdout.splitlines() if line.startswith("120000 ")]
    return [(path, os.readlink(ROOT / path)) for path in links if (ROOT / path).is_symlink()]


def test_no_tracked_link_leaves_the_repository() -> None:
    leaving = [(path, target) for path, target in _tracked_links()
               if os.path.isabs(target) or not (ROOT / path).parent.joinpath(target).resolve().is_relative_to(ROOT)]
    assert not leaving, f"tracked links pointing outside the repository: {leaving}"


def _name(requirement: str) -> str:
    """The normalised distribution name of a PEP 508 requirement (PEP 503: lower case, runs of -_. as -)."""
    match = re.match(r"\s*([A-Za-z0-9][A-Za-z0-9._-]*)", requirement)
    assert match, requirement
    return re.sub(r"[-_.]+", "-", match.group(1)).lower()


def test_the_lock_pins_every_declared_dependency_exactly() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    declared = {_name(r) for r in project["dependencies"]}
    declared |= {_name(r) for extra in project["optional-dependencies"].values() for r in extra}
    lines = [ln.strip() for ln in (ROOT / "requirements.lock").read_text().splitlines()]
    pins = dict(ln.split("==", 1) for ln in lines if ln and not ln.startswith("#"))
    assert all(re.fullmatch(r"[0-9][0-9A-Za-z.+!-]*", v) for v in pins.values()), "every pin is an exact version"
    pinned = {_name(name) for name in pins}
    assert declared <= pinned, f"declared but not pinned in requirements.lock: {sorted(declared - pinned)}"
    assert "s2r" not in pinned and "pip" in pinned


def test_the_makefile_installs_from_the_lock() -> None:
    makefile = (ROOT / "Makefile").read_text()
    installs = [ln for ln in makefile.splitlines() if "$(BIN)/python -m pip install" in ln]
    assert installs and all("-c $(LOCK)" in ln for ln in installs), installs

"""calib's stages import one way: report -> solve -> detect, and inside solve: pipelines -> honesty -> solvers ->
views/synth (and detect's modules without a cycle)."""

from __future__ import annotations

from pathlib import Path

from tests.test_import_graph import module_imports

CALIB = Path(__file__).resolve().parents[2] / "s2r" / "calib"
#: A stage may import only from stages with a lower rank (or from itself); a module belongs to the longest stage its
#: path starts with (``solve/views.py`` to ``solve``, ``solve/honesty/heldout.py`` to ``solve.honesty``).
STAGES = {"detect": 0, "solve": 1, "solve.solvers": 2, "solve.honesty": 3, "solve.pipelines": 4, "report": 5}


def _stage(dotted: str) -> str | None:
    """The stage of a module named ``dotted`` inside calib (``solve.honesty.heldout``); None outside any."""
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in STAGES:
            return ".".join(parts[:n])
    return None


def test_every_calib_module_is_in_a_stage() -> None:
    loose = [p.name for p in CALIB.glob("*.py") if p.name != "__init__.py"]
    assert not loose, f"put these into detect/, solve/ or report/: {loose}"


def test_stages_import_one_way() -> None:
    wrong = []
    for path in sorted(CALIB.rglob("*.py")):
        stage = _stage(".".join(path.relative_to(CALIB).with_suffix("").parts))
        if stage is None:
            continue
        for name in module_imports(path):
            if not name.startswith("s2r.calib"):
                continue
            target = _stage(name.removeprefix("s2r.calib").removeprefix("."))
            if target != stage and (target is None or STAGES[target] > STAGES[stage]):
                wrong.append(f"{path.relative_to(CALIB)} ({stage}) imports {name}")
    assert not wrong, "\n".join(wrong)


def test_detect_has_no_import_cycle() -> None:
    edges = {p.stem: {n.split(".")[3] for n in module_imports(p) if n.startswith("s2r.calib.detect.")}
             for p in (CALIB / "detect").glob("*.py") if p.stem != "__init__"}

    def reaches(start: str, goal: str, seen: set[str]) -> bool:
        return any(n == goal or (n not in seen and reaches(n, goal, seen | {n})) for n in edges.get(start, ()))

    cyclic = sorted(m for m in edges if reaches(m, m, {m}))
    assert not cyclic, f"import cycle through {cyclic}"

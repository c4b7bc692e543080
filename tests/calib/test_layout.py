"""calib's stages import one way: report -> solve -> detect (and detect's modules without a cycle)."""

from __future__ import annotations

from pathlib import Path

from tests.test_import_graph import module_imports

CALIB = Path(__file__).resolve().parents[2] / "s2r" / "calib"
#: A stage may import only from stages with a lower rank.
STAGES = {"detect": 0, "solve": 1, "report": 2}


def test_every_calib_module_is_in_a_stage() -> None:
    loose = [p.name for p in CALIB.glob("*.py") if p.name != "__init__.py"]
    assert not loose, f"put these into detect/, solve/ or report/: {loose}"


def test_stages_import_one_way() -> None:
    wrong = []
    for stage, rank in STAGES.items():
        for path in sorted((CALIB / stage).glob("*.py")):
            for name in module_imports(path):
                parts = name.split(".")
                if parts[:2] == ["s2r", "calib"] and (len(parts) < 3 or STAGES.get(parts[2], 99) > rank):
                    wrong.append(f"{stage}/{path.name} imports {name}")
    assert not wrong, "\n".join(wrong)


def test_detect_has_no_import_cycle() -> None:
    edges = {p.stem: {n.split(".")[3] for n in module_imports(p) if n.startswith("s2r.calib.detect.")}
             for p in (CALIB / "detect").glob("*.py") if p.stem != "__init__"}

    def reaches(start: str, goal: str, seen: set[str]) -> bool:
        return any(n == goal or (n not in seen and reaches(n, goal, seen | {n})) for n in edges.get(start, ()))

    cyclic = sorted(m for m in edges if reaches(m, m, {m}))
    assert not cyclic, f"import cycle through {cyclic}"

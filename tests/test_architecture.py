"""The direction of imports (SPEC Layout): doodle.core is the ground floor, doodle.app the
roof, and the stages in between import downwards only — the contracts in pyproject.toml,
checked by import-linter."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_import_contracts_are_kept(monkeypatch, capsys):
    from importlinter.cli import lint_imports

    monkeypatch.chdir(ROOT)
    code = lint_imports(config_filename=str(ROOT / "pyproject.toml"))
    out = capsys.readouterr().out
    assert code == 0, out
    assert "2 kept, 0 broken" in out


def test_the_core_imports_nothing_of_ours():
    import ast

    ours = ("doodle", "grammar", "laban", "retarget", "library")
    for path in (ROOT / "doodle" / "core").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else (
                [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            for name in names:
                assert name.split(".")[0] not in ours or name.startswith("doodle.core"), f"{path.name} imports {name}"

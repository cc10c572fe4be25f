"""A user's type checker sees the package's types (PEP 561).

Every top-level package carries ``py.typed``; the public names that the packages import on first
use (a lazy table and PEP 562 ``__getattr__``) are also imported under ``TYPE_CHECKING``, so a type
checker gets their real signatures instead of ``Any``. The project's own check of the public API is
``mypy`` with ``[tool.mypy]`` in ``pyproject.toml`` (run by CI, not by this file).
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("analytic", "model_xml", "mj_bridge", "validation")
TABLE_NAMES = ("_LAZY", "_PUBLIC", "_TABLE")

USER_CODE = """\
from analytic import Scene, load_scene, simulate
from mj_bridge.plants import registered
from validation import run_validation

scene: Scene = load_scene("paper_example1")
reveal_type(simulate(scene))
reveal_type(run_validation("paper_example1", "out"))
reveal_type(registered())
"""

USER_CONFIG = """\
[mypy]
strict = True
# only this project's packages are analysed (numpy, MuJoCo, ... are skipped: Any), so the check
# takes seconds, not the ~20 s of reading numpy's stubs cold
follow_imports = skip
[mypy-analytic,analytic.*,model_xml,model_xml.*,mj_bridge,mj_bridge.*,validation,validation.*]
follow_imports = silent
"""


def test_every_package_is_marked_typed():
    missing = [p for p in PACKAGES if not (ROOT / p / "py.typed").is_file()]
    assert not missing, f"no py.typed in {missing}"


def _lazy_tables() -> list[tuple[Path, dict[str, str], set[tuple[str, str]]]]:
    """Each package ``__init__`` with a lazy table: the table (name -> module) and the
    ``(module, name)`` pairs it imports under ``if TYPE_CHECKING:``."""
    found = []
    for pkg in PACKAGES:
        for init in sorted((ROOT / pkg).rglob("__init__.py")):
            tree = ast.parse(init.read_text(encoding="utf-8"))
            table: dict[str, str] = {}
            typed: set[tuple[str, str]] = set()
            for node in tree.body:
                if (
                    isinstance(node, ast.Assign)
                    and len(node.targets) == 1
                    and isinstance(node.targets[0], ast.Name)
                    and node.targets[0].id in TABLE_NAMES
                    and isinstance(node.value, ast.Dict)
                ):
                    pairs = zip(node.value.keys, node.value.values, strict=True)
                    table = {ast.literal_eval(k): ast.literal_eval(v) for k, v in pairs}
                if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
                    for imp in node.body:
                        if isinstance(imp, ast.ImportFrom) and imp.module:
                            typed |= {(imp.module, a.asname or a.name) for a in imp.names}
            if table:
                found.append((init, table, typed))
    return found


def test_every_lazy_name_is_typed():
    """A name added to a lazy table and not to its ``TYPE_CHECKING`` imports would be ``Any`` to
    every user's type checker, silently."""
    tables = _lazy_tables()
    assert len(tables) >= 4  # analytic, model_xml, mj_bridge, validation at least
    bad = [
        f"{init.relative_to(ROOT)}: {name!r} from {module} not imported under TYPE_CHECKING"
        for init, table, typed in tables
        for name, module in table.items()
        if (module, name) not in typed
    ]
    assert not bad, "\n".join(bad)


def test_a_users_mypy_sees_the_types(tmp_path, request):
    """mypy, run as a user's would (outside the project, the packages found on the Python path as
    installed ones), takes the packages as typed (no ``import-untyped``) and gives the lazily
    imported names their real types. Its cache is kept in pytest's (a few seconds cold, as in CI;
    under one warm)."""
    cache = getattr(request.config, "cache", None)  # None under -p no:cacheprovider
    cache_dir = cache.mkdir("mypy_user") if cache is not None else tmp_path / ".cache"
    (tmp_path / "user.py").write_text(USER_CODE, encoding="utf-8")
    (tmp_path / "mypy.ini").write_text(USER_CONFIG, encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if not k.startswith("MYPY")}
    env["PYTHONPATH"] = str(ROOT)  # the tree under test, ahead of an installed copy
    mypy = [
        sys.executable,
        "-m",
        "mypy",
        "--config-file",
        "mypy.ini",
        "--cache-dir",
        str(cache_dir),
    ]
    proc = subprocess.run(
        [*mypy, "--python-executable", sys.executable, "user.py"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    out = proc.stdout + proc.stderr
    assert "import-untyped" not in out and "import-not-found" not in out, out
    assert proc.returncode == 0, out
    for revealed in (
        "analytic.trajectory.Trajectory",
        "validation.validate.records.ValidationResult",
        "dict[str, type[analytic.plant.Plant]]",
    ):
        assert f'Revealed type is "{revealed}"' in out, textwrap.indent(out, "  ")


@pytest.mark.slow
def test_the_wheel_ships_the_marker_and_the_data(tmp_path):
    """A built wheel holds ``py.typed`` in every package, the built-in and hard-case scenes and
    the JSON schemas (package data), and builds without setuptools' warning about data directories
    left out of ``packages``. Built from a clone of the committed tree (a build writes
    ``validation/_version.py``); the build requirements come from the package index."""
    import zipfile

    src = tmp_path / "src"
    subprocess.run(["git", "clone", "--quiet", str(ROOT), str(src)], check=True, timeout=120)
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "-v", "--no-deps", "-w", str(tmp_path), "."],
        cwd=src,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "absent from the `packages` configuration" not in proc.stdout + proc.stderr
    (wheel,) = tmp_path.glob("*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    assert {f"{p}/py.typed" for p in PACKAGES} <= names
    for pattern in ("analytic/scenes/", "validation/scenes/hard/", "validation/report/schemas/"):
        assert any(n.startswith(pattern) for n in names), f"no {pattern}* in {wheel.name}"
    assert "validation/scenes/scene.schema.json" in names  # the scene format's schema, for editors

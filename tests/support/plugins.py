"""Installing a test's plant plugin as an installer would, without a build backend or network."""

from __future__ import annotations

import shutil
import tomllib
from pathlib import Path


def install_project(project: Path, target: Path) -> Path:
    """Install a pure-Python, single-module project into ``target`` as an installer does: its
    modules (``[tool.setuptools] py-modules``) and a ``<name>-<version>.dist-info`` with
    ``METADATA`` and the ``entry_points.txt`` of its ``[project.entry-points]``; ``target`` on
    ``PYTHONPATH`` then shows it to ``importlib.metadata``. (``pip install --target`` needs a
    build backend with ``bdist_wheel``, which the test environment does not promise offline.)"""
    meta = tomllib.loads((project / "pyproject.toml").read_text())
    proj = meta["project"]
    target.mkdir(parents=True)
    for mod in meta["tool"]["setuptools"]["py-modules"]:
        shutil.copy(project / f"{mod}.py", target / f"{mod}.py")
    info = target / f"{proj['name'].replace('-', '_')}-{proj['version']}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(
        f"Metadata-Version: 2.1\nName: {proj['name']}\nVersion: {proj['version']}\n"
    )
    groups = [
        f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in eps.items())
        for group, eps in proj["entry-points"].items()
    ]
    (info / "entry_points.txt").write_text("\n".join(groups))
    return target

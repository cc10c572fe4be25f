"""The sweep's reference cache key (:func:`validation.studies.sweep.reference.code_fingerprint`)."""

from __future__ import annotations

import types

from validation.studies.sweep import reference


def _tree(tmp_path):
    pkg = tmp_path / "analytic"
    (pkg / "scene").mkdir(parents=True)
    (pkg / "kernel").mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "model.py").write_text("M = 1\n")
    (pkg / "scene" / "loading.py").write_text("DEFAULT = 1\n")
    (pkg / "kernel" / "gauss.py").write_text("K = 1\n")
    return pkg


def test_a_change_anywhere_in_analytic_changes_the_key(tmp_path, monkeypatch):
    """The reference is the analytic plant's run, so every module of ``analytic`` is part of the
    key, those of its subpackages (the scene format, the kernel) included: a cached reference is
    never reused after the code that made it changed."""
    pkg = _tree(tmp_path)
    monkeypatch.setattr(reference, "analytic", types.SimpleNamespace(__file__=str(pkg / "__init__.py")))
    base = reference.code_fingerprint()
    assert reference.code_fingerprint() == base  # a key, not a clock
    for rel in ("model.py", "scene/loading.py", "kernel/gauss.py"):
        f = pkg / rel
        old = f.read_text()
        f.write_text(old.replace("1", "2"))
        assert reference.code_fingerprint() != base, f"{rel} is not part of the key"
        f.write_text(old)
        assert reference.code_fingerprint() == base


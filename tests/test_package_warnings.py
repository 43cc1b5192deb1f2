"""Every warning the package issues has a category of its own, derived from MpegFaWarning."""
from __future__ import annotations

import ast
from pathlib import Path

import mpeg4fa
from mpeg4fa import errors


def test_every_warning_the_package_issues_is_a_package_warning():
    """warnings.warn in the package names a category derived from MpegFaWarning (the CLI prints those)."""
    root = Path(mpeg4fa.__file__).parent
    builtin = {"UserWarning", "Warning", "RuntimeWarning", "DeprecationWarning"}
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "attr", None) == "warn":
                category = node.args[1] if len(node.args) > 1 else None
                name = getattr(category, "id", getattr(category, "attr", None))
                assert name is not None and name not in builtin, f"{path}:{node.lineno}: warning without a package category"
    assert issubclass(errors.MpegFaWarning, UserWarning)

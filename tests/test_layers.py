"""The import rule of each layer (docs/ARCHITECTURE.md, "Layers"), read from the source.

Every ``import`` and ``from ... import`` statement of a package, at any depth (lazy imports
inside functions included), must name a module its layer may use:

* ``core`` uses no other layer of the project;
* ``drivers`` uses ``core`` and itself;
* ``controller`` uses ``core``, itself and, of ``drivers``, only the registry (which imports
  a driver by name when a device is built): never a concrete driver, never the simulator;
* ``evaluation`` may use every layer; no product layer imports it;
* no package imports ``tests`` or ``scripts``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PROJECT = ("core", "drivers", "controller", "evaluation", "configs", "tests", "scripts")
ALLOWED = {
    "core": ("core",),
    "drivers": ("core", "drivers"),
    "controller": ("core", "controller", "drivers.registry"),
    "evaluation": ("core", "drivers", "controller", "evaluation", "configs"),
}


def imported_modules(path: Path) -> list[tuple[int, str]]:
    """(line, dotted name) of every absolute import in ``path``: the module, or for
    ``from M import N`` the name ``M.N``."""
    tree = ast.parse(path.read_text(), filename=str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.extend((node.lineno, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            # ``from drivers import registry`` imports the module drivers.registry
            found.extend((node.lineno, f"{node.module}.{alias.name}") for alias in node.names)
    return found


def allowed(module: str, layer: str) -> bool:
    if module.split(".")[0] not in PROJECT:
        return True  # a third-party or standard-library module
    return any(module == ok or module.startswith(ok + ".") for ok in ALLOWED[layer])


def violations(layer: str) -> list[str]:
    return [
        f"{path.relative_to(ROOT)}:{line}: imports {module}"
        for path in sorted((ROOT / layer).rglob("*.py"))
        for line, module in imported_modules(path)
        if not allowed(module, layer)
    ]


@pytest.mark.parametrize("layer", sorted(ALLOWED))
def test_each_layer_imports_only_what_its_rule_allows(layer):
    assert violations(layer) == []


def test_the_rule_catches_a_forbidden_import(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("def f():\n    from drivers.sim.twins.arm import SimArm\n")
    ((line, module),) = imported_modules(bad)
    assert (line, module) == (2, "drivers.sim.twins.arm.SimArm")
    assert not allowed(module, "controller") and not allowed(module, "core")
    assert allowed("drivers.registry", "controller") and not allowed("controller", "drivers")

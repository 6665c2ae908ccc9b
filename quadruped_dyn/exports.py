"""How each subpackage exports its public names: listed in ``__all__``, imported on first use.

A subpackage's ``__init__`` names, per module, the public names it exports; ``from
quadruped_dyn.dynamics import reduced_model`` then imports ``dynamics.reduced`` only when asked,
so importing a subpackage stays cheap (``import quadruped_dyn`` never pulls in scipy or
matplotlib, ``references`` never MuJoCo or iDynTree).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(package: str, modules: Mapping[str, tuple[str, ...]]
                 ) -> tuple[list[str], Callable[[str], Any], Callable[[], list[str]]]:
    """(``__all__``, ``__getattr__``, ``__dir__``) of ``package`` for ``modules``: module name ->
    the public names it exports (each name exported by one module only)."""
    owner = {name: module for module, names in modules.items() for name in names}
    if len(owner) != sum(len(names) for names in modules.values()):
        raise AssertionError(f"{package}: a name is exported by two modules")

    def getattr_(name: str) -> Any:
        if name not in owner:
            raise AttributeError(f"module '{package}' has no attribute '{name}'")
        return getattr(importlib.import_module(f"{package}.{owner[name]}"), name)

    def dir_() -> list[str]:
        return sorted(owner)

    return sorted(owner), getattr_, dir_

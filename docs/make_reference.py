"""Write the API reference's module pages (scenario code, not API).

    python docs/make_reference.py

One page per public module of ``gdimitate`` (the modules in ``gdimitate.__all__``):
``docs/reference/<module>.md``, the module's docstring and every name of the module's own
``__all__``, each as a mkdocstrings entry under the module that defines it (a function that
shares its name with a module, as ``gdimitate.sim.simulate``, is documented from its home).
``docs/reference/index.md`` (written by hand) holds ``gdimitate.__all__`` itself.
``tests/project/test_docs.py`` checks that every page lists its module's ``__all__``, so a new
public name fails the suite until this script is run again.
"""

from __future__ import annotations

import inspect
import types
from pathlib import Path

import gdimitate

REFERENCE = Path(__file__).resolve().parent / "reference"


def public_modules() -> list[str]:
    """The modules among ``gdimitate.__all__``, in its order."""
    return [n for n in gdimitate.__all__ if isinstance(getattr(gdimitate, n), types.ModuleType)]


def home(module: types.ModuleType, name: str) -> str:
    """The path mkdocstrings documents ``module.name`` from: a class's or function's own
    module, else the name under ``module``."""
    obj = getattr(module, name)
    if (inspect.isclass(obj) or inspect.isfunction(obj)) and obj.__name__ == name:
        return f"{obj.__module__}.{name}"
    return f"{module.__name__}.{name}"


def page(name: str) -> str:
    """The markdown of the page of public module ``name``."""
    module = getattr(gdimitate, name)
    lines = [f"# gdimitate.{name}", "", f"::: {module.__name__}", "    options:",
             "      show_root_heading: false", "      members: false", ""]
    for member in module.__all__:
        lines += [f"::: {home(module, member)}", ""]
    return "\n".join(lines)


def main() -> None:
    for name in public_modules():
        path = REFERENCE / f"{name}.md"
        path.write_text(page(name))
        print(f"{path.relative_to(REFERENCE.parents[1])}: {len(getattr(gdimitate, name).__all__)}"
              " names")


if __name__ == "__main__":
    main()

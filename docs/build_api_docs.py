"""Build touchbench's API reference (HTML, with pdoc) into a folder; any warning fails the build.

    python docs/build_api_docs.py [OUT]        (default build/api; ``make api-docs``)

Every public module is documented (a module or package whose name starts
with ``_`` is private). The package root's page holds the user-level names
(``touchbench.load_dataset``, ``touchbench.run_protocol``...). pdoc walks a
package's submodules by itself unless the package's ``__all__`` leaves them
out, so those are named explicitly. Docstrings are reStructuredText
(``code``, :mod:`roles`), pdoc's default format.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import re
import sys
import warnings
from pathlib import Path


# the reference of this checkout, whichever touchbench the environment has installed
REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


def public_modules() -> list[str]:
    """``touchbench`` and every submodule without a private part in its name."""
    import touchbench

    found = pkgutil.walk_packages(touchbench.__path__, "touchbench.")
    return ["touchbench"] + sorted(m.name for m in found if not any(p.startswith("_") for p in m.name.split(".")))


def specs(modules: list[str]) -> list[str]:
    """The modules pdoc must be given: those its walk from their parent package would not reach."""
    out = []
    for name in modules:
        parent, _, leaf = name.rpartition(".")
        if parent:
            listed = getattr(importlib.import_module(parent), "__all__", None)
            if listed is None or leaf in listed:
                continue
        out.append(name)
    return out


def build(out: Path) -> list[str]:
    """Write the reference into ``out``; the warnings raised while importing and rendering."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        import pdoc
        import pdoc.render

        import touchbench

        pdoc.render.configure(docformat="restructuredtext", footer_text=f"touchbench {touchbench.__version__}")
        pdoc.pdoc(*specs(public_modules()), output_directory=out)
    problems = [f"{w.filename}:{w.lineno}: {w.category.__name__}: {w.message}" for w in caught]
    # pdoc keeps the "~" of a Sphinx role (:class:`~a.B`) in the page: write :class:`a.B`
    tilde_role = re.compile(r"<code>~(<a |[A-Za-z_]\w*(\.\w+)+</code>)")
    problems += [f"{page}: a role written with '~', which pdoc prints as is"
                 for page in sorted(out.rglob("*.html")) if tilde_role.search(page.read_text(encoding="utf-8"))]
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", default="build/api", type=Path, help="output folder (default build/api)")
    out = parser.parse_args(argv).out
    problems = build(out)
    for p in problems:
        print(p, file=sys.stderr)
    if problems:
        print(f"{len(problems)} warning(s) while building the API reference: fix them", file=sys.stderr)
        return 1
    print(f"wrote {out / 'index.html'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

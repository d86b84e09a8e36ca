"""The generated pages of the documentation's reference, and the MkDocs hook that keeps
them true.

``python tools/docs_reference.py write`` writes them; ``python tools/docs_reference.py
check`` exits 1 naming every page that differs from what the package generates now. The
site's build (``mkdocs build``, configured in mkdocs.yml) runs the same check and fails on a
stale page, so the command-line reference cannot drift from the parser.
"""

from __future__ import annotations

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"


def generated_pages() -> dict[Path, str]:
    """Every generated page: path under docs/ -> its text."""
    return {}


def stale_pages() -> list[Path]:
    """The generated pages whose committed text differs from what the package generates."""
    return [
        path
        for path, text in generated_pages().items()
        if not (DOCS / path).exists() or (DOCS / path).read_text() != text
    ]


def on_pre_build(config, **kwargs) -> None:
    """MkDocs hook: a stale generated page is an error (the build stops, naming it)."""
    from mkdocs.exceptions import PluginError

    stale = stale_pages()
    if stale:
        names = ", ".join(str(p) for p in stale)
        raise PluginError(
            f"stale generated pages: {names}; run python tools/docs_reference.py write"
        )


def main(argv: list[str]) -> int:
    if argv == ["write"]:
        for path, text in generated_pages().items():
            (DOCS / path).parent.mkdir(parents=True, exist_ok=True)
            (DOCS / path).write_text(text)
        return 0
    if argv == ["check"]:
        stale = stale_pages()
        for path in stale:
            print(f"stale: docs/{path}")
        return 1 if stale else 0
    print("usage: python tools/docs_reference.py {write,check}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

"""The documentation cannot rot: every code block of the tutorials, the how-to guides and the
README runs here, as a reader would run it, in a fresh directory per page.

How a page's blocks run (CONTRIBUTING.md, "Documentation", says the same):

- a ``python`` block runs in the page's one namespace, blocks in page order, so a later block
  may use what an earlier one made, in the page's directory and with it on the import path, so
  it may import a file the page saved;
- a block with a title (```` ```python title="my_gaits.py" ````, or ``toml``) is a file the
  reader saves: it is written to the page's directory under that name, not run;
- a ``bash`` block is commands typed in a shell: ``scoutsim ...`` runs the command line in
  this process (``PYTHONPATH=.`` in front puts the page's directory on the import path, for
  the command and its workers), ``python FILE ...`` runs a script as a new process; the
  set-up commands of a fresh machine (``python3 -m venv``, ``. .venv/bin/activate``,
  ``pip install``) are what this test environment already did, and ``pytest`` is the
  command running these tests: both are skipped; any other
  command fails the test, so a page cannot show a command nobody ran;
- ``text`` blocks (printed output, a directory listing) are not run.

Every command must succeed (exit 0), and every ``assert`` in a block must hold: a tutorial
that says "check that it bounds" checks it here.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
PAGES = sorted(
    [REPO / "README.md", *(DOCS / "tutorials").glob("*.md"), *(DOCS / "how-to").glob("*.md")]
)

#: the set-up commands of a fresh machine, done already by the environment that runs these
#: tests, and the test command itself (these tests are part of what it runs)
SET_UP = ("python3 -m venv", "python -m venv", ". .venv/bin/activate", "source .venv", "pip ")
TEST_COMMAND = ("pytest",)
#: a script run as its own process gets at most this long (a bound on a hung process, not a
#: timing check: a cold cache compiles the core first)
SCRIPT_TIMEOUT_S = 900

FENCE = re.compile(r"^(?P<indent> *)(?P<fence>```+)(?P<info>[^`\n]*)$")
TITLE = re.compile(r'title="(?P<title>[^"]+)"')


@dataclass(frozen=True)
class Block:
    """One fenced code block of a page: its language, its title (a file to save) or none,
    its text and the line it starts on."""

    language: str
    title: str | None
    text: str
    line: int


def code_blocks(page: Path) -> list[Block]:
    """The fenced code blocks of a Markdown page, in order."""
    blocks: list[Block] = []
    lines = page.read_text().splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, fence, info = len(m["indent"]), m["fence"], m["info"].strip()
        start, body = i + 1, []
        i += 1
        while i < len(lines) and lines[i].strip() != fence:
            body.append(lines[i][indent:])
            i += 1
        language = info.split()[0] if info else ""
        t = TITLE.search(info)
        blocks.append(Block(language, t["title"] if t else None, "\n".join(body) + "\n", start))
        i += 1
    return blocks


def shell_commands(text: str) -> list[str]:
    """The commands of a shell block: continuation lines joined, comments and blank lines
    dropped, ``a && b`` split into its commands."""
    joined = re.sub(r"\s*\\\n\s*", " ", text)
    commands = []
    for line in joined.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        line = line.removeprefix("$ ")
        commands += [c.strip() for c in line.split("&&") if c.strip()]
    return commands


def run_shell(command: str, where: Path, monkeypatch) -> None:
    """Run one command of a shell block in ``where`` (see the module docstring)."""
    if command.startswith(SET_UP + TEST_COMMAND):
        return
    words = shlex.split(command, comments=True)
    env_words = []
    while words and re.fullmatch(r"[A-Z_]+=\S*", words[0]):
        env_words.append(words.pop(0))
    assert words, f"an empty command: {command!r}"
    for word in env_words:
        name, value = word.split("=", 1)
        assert name == "PYTHONPATH" and value == ".", f"only PYTHONPATH=. is run: {command!r}"
        monkeypatch.setenv("PYTHONPATH", str(where))
        monkeypatch.syspath_prepend(str(where))
    if words[0] == "scoutsim":
        from scoutsim.cli import main

        code = main(words[1:])
        assert code == 0, f"{command!r} exited {code}"
    elif words[0] in ("python", "python3"):
        out = subprocess.run(
            [sys.executable, *words[1:]],
            cwd=where,
            capture_output=True,
            text=True,
            timeout=SCRIPT_TIMEOUT_S,
            env={**os.environ, "PYTHONPATH": str(where)} if env_words else None,
        )
        assert out.returncode == 0, (
            f"{command!r} exited {out.returncode}\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}"
        )
    else:
        pytest.fail(f"the documentation runs a command these tests cannot run: {command!r}")


def _forget_modules_under(directory: Path) -> None:
    """Drop from ``sys.modules`` the modules imported from files under ``directory``."""
    for name, module in list(sys.modules.items()):
        where = getattr(module, "__file__", None)
        if where and Path(where).resolve().is_relative_to(directory.resolve()):
            del sys.modules[name]


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(REPO)) for p in PAGES])
def test_every_code_block_of_the_page_runs(page, tmp_path, monkeypatch, request):
    """The page's code blocks run in order and every command and assertion succeeds."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    # a reader's Python runs in the directory the page's files are saved in, so it imports
    # them; the modules a page saved are forgotten after it (another page's file of the
    # same name is another module)
    monkeypatch.syspath_prepend(str(tmp_path))
    request.addfinalizer(lambda: _forget_modules_under(tmp_path))
    namespace: dict = {"__name__": "__docs__"}
    blocks = code_blocks(page)
    for block in blocks:
        where = f"{page.relative_to(REPO)}:{block.line}"
        if block.title is not None:
            (tmp_path / block.title).parent.mkdir(parents=True, exist_ok=True)
            (tmp_path / block.title).write_text(block.text)
        elif block.language == "python":
            exec(compile(block.text, where, "exec"), namespace)
        elif block.language in ("bash", "sh", "shell", "console"):
            for command in shell_commands(block.text):
                run_shell(command, tmp_path, monkeypatch)
        elif block.language not in ("text", "toml", "json", ""):
            pytest.fail(f"{where}: a {block.language!r} block: mark output as ```text")
    import matplotlib.pyplot as plt

    plt.close("all")


def test_the_runner_reads_blocks_as_the_page_shows_them(tmp_path):
    """Fences, titles, indented blocks and shell continuations are read as written."""
    page = tmp_path / "p.md"
    page.write_text(
        "text\n```python\nx = 1\n```\n\n"
        '```python title="m.py"\ndef f():\n    return 2\n```\n'
        "1. a step\n\n    ```bash\n    scoutsim run \\\n      --duration 1 && scoutsim cache\n    ```\n"
    )
    b = code_blocks(page)
    assert [(x.language, x.title) for x in b] == [
        ("python", None),
        ("python", "m.py"),
        ("bash", None),
    ]
    assert b[1].text == "def f():\n    return 2\n"
    assert shell_commands(b[2].text) == ["scoutsim run --duration 1", "scoutsim cache"]


#: the user's pages: the site's pages and the README (the changelog and benchmarks/README.md
#: keep the history)
USER_PAGES = sorted([REPO / "README.md", *DOCS.rglob("*.md")])
#: a word of seven or more hexadecimal digits with a digit and a letter: a commit
COMMIT = re.compile(r"\b(?=[0-9a-f]*[0-9])(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}\b")
#: how development history reads in prose
HISTORY = re.compile(r"earlier versions?|in an earlier|\bmended\b|\bsession\b|issue #?\d", re.I)


@pytest.mark.parametrize("page", USER_PAGES, ids=[str(p.relative_to(REPO)) for p in USER_PAGES])
def test_user_pages_carry_no_commit_hashes_or_history(page):
    """A user's page says what the package does, not how it got there."""
    text = page.read_text()
    found = [m.group(0) for m in COMMIT.finditer(text)] + [
        m.group(0) for m in HISTORY.finditer(text)
    ]
    assert not found, f"{page.relative_to(REPO)}: {found}"

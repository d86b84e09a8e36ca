"""The on-disk cache of the compiled core (Numba): where each module's machine code is
kept, under which digest, and what is removed when.

The cache is kept per module of the compiled core, in a directory named by a digest of that
module's source and of every core module it imports, directly or through others
(:func:`module_digests`): Numba by itself checks only the timestamp of a function's own
file, so a cached function that inlines or links a callee from another module would keep
the old callee after that module is edited (a stale result, silently). With the digest, an
edit of a module compiles afresh that module and the modules that import it, and loads the
rest from the cache (an edit of ``loop.py`` recompiles the run loop alone, an edit of
``_core/model/evaluate.py`` nearly everything). The directories are
``scoutsim/__pycache__/numba/<module>-<digest>``, or, where the package is not writable,
under ``~/.cache/scoutsim/numba``. The function's cache locator
(:class:`_CoreCacheLocator`, :func:`install_cache_locator`) puts them there, whatever
Numba's own cache directory setting is, which is left alone (it is the user's, for their
own functions).

A ``NUMBA_CACHE_DIR`` set by the user is where the cache goes, in
``$NUMBA_CACHE_DIR/scoutsim-numba/<module>-<digest>`` (:func:`user_cache_dir`). Such a
directory may be shared (by other programs, or by checkouts of other scoutsim versions
running at the same time), so only directories of ours (``<module>-<digest>`` of a core
module, and the ``scoutsim-numba-<digest>`` of older versions) are ever removed there, and
only those of other digests that nothing has written to for a day
(:data:`STALE_USER_CACHE_S`); everything else in it is left alone.

Nothing is removed when the package is imported. The directories of other digests (and
the whole-core directories of older versions) are removed by :func:`clean_cache`, which
runs once per process when the core is first compiled or loaded from the cache, and which
``scoutsim cache --clean`` runs on request.
"""

from __future__ import annotations

import ast
import hashlib
import os
import re
import shutil
import threading
import time
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1]
#: the sources of the compiled core (a change in any of them invalidates the cache of the
#: modules that import it)
CORE_SOURCES = (
    "_core/model/*.py",
    "_core/numerics/*.py",
    "_core/loop.py",
    "control/*.py",
    "_numba/*.py",
)


def _core_files(package: Path) -> list[Path]:
    return sorted({f for pattern in CORE_SOURCES for f in package.glob(pattern)})


def core_digest(package: Path = PACKAGE) -> str:
    """Digest of the compiled core's sources (names and contents) under ``package``."""
    h = hashlib.sha256()
    for f in _core_files(package):
        h.update(f.relative_to(package).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def _module_name(rel: str) -> str:
    """``model/evaluate.py`` -> ``model.evaluate``, ``control/__init__.py`` -> ``control``."""
    parts = rel[:-3].split("/")
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts) or "__init__"


def _imported(rel: str, source: bytes, known: set[str]) -> set[str]:
    """The core modules (relative paths in ``known``) that the module ``rel`` imports
    anywhere in its source, read statically: ``from .x import y`` names ``x`` and, if it is
    a module, ``x/y``; a package import names its ``__init__``."""
    pkg = rel.split("/")[:-1]
    out = set()

    def add(parts):
        for cand in ("/".join(parts) + ".py", "/".join(parts + ["__init__"]) + ".py"):
            if cand in known:
                out.add(cand)

    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                if node.level - 1 > len(pkg):
                    continue
                base = pkg[: len(pkg) - (node.level - 1)]
            elif node.module and node.module.split(".")[0] == PACKAGE.name:
                base = []
            else:
                continue
            mod = base + (node.module.split(".") if node.module else [])
            if not node.level:
                mod = mod[1:]
            for i in range(1, len(mod) + 1):
                add(mod[:i])
            for alias in node.names:
                add(mod + [alias.name])
        elif isinstance(node, ast.Import):
            for alias in node.names:
                mod = alias.name.split(".")
                if mod[0] == PACKAGE.name:
                    for i in range(2, len(mod) + 1):
                        add(mod[1:i])
    out.discard(rel)
    return out


def _import_graph(sources: dict[str, bytes], memo: Path | None) -> dict[str, set[str]]:
    """The core modules each core module imports (:func:`_imported`), reading the sources'
    syntax only for those not in ``memo`` (a file of earlier answers, by source digest:
    parsing every module takes about 0.1 s, too long for every start)."""
    import json

    known = sorted(sources)
    layout = hashlib.sha256("\n".join(known).encode()).hexdigest()[:16]
    shas = {rel: hashlib.sha256(src).hexdigest()[:32] for rel, src in sources.items()}
    old = {}
    if memo is not None:
        try:
            data = json.loads(memo.read_text())
            if data.get("layout") == layout:
                old = data.get("modules", {})
        except (OSError, ValueError, AttributeError):
            old = {}
    deps, changed = {}, False
    for rel, src in sources.items():
        entry = old.get(rel)
        if isinstance(entry, dict) and entry.get("sha") == shas[rel]:
            deps[rel] = set(entry.get("imports", ())) & set(known)
        else:
            deps[rel] = _imported(rel, src, set(known))
            changed = True
    if memo is not None and (changed or set(old) != set(sources)):
        try:
            memo.parent.mkdir(parents=True, exist_ok=True)
            tmp = memo.with_name(f"{memo.name}.{os.getpid()}.tmp")
            tmp.write_text(
                json.dumps(
                    {
                        "layout": layout,
                        "modules": {
                            rel: {"sha": shas[rel], "imports": sorted(deps[rel])} for rel in known
                        },
                    }
                )
            )
            os.replace(tmp, memo)
        except OSError:
            pass
    return deps


def module_digests(package: Path = PACKAGE, memo: Path | None = None) -> dict[str, str]:
    """For every module of the compiled core (its path relative to ``package``), a digest of
    its source and of the sources of every core module it imports, directly or through
    others: what its compiled functions can depend on (the constants they read, the
    functions they inline or link). ``memo``: a file that keeps the import graph between
    processes (:func:`_import_graph`)."""
    sources = {f.relative_to(package).as_posix(): f.read_bytes() for f in _core_files(package)}
    deps = _import_graph(sources, memo)
    out = {}
    for rel in sources:
        seen, stack = {rel}, [rel]
        while stack:
            for d in deps[stack.pop()]:
                if d not in seen:
                    seen.add(d)
                    stack.append(d)
        h = hashlib.sha256()
        for d in sorted(seen):
            h.update(d.encode())
            h.update(b"\0")
            h.update(sources[d])
        out[rel] = h.hexdigest()[:16]
    return out


#: name of this package's cache directory inside a ``NUMBA_CACHE_DIR`` set by the user
USER_CACHE_NAME = "scoutsim-numba"
#: name of the cache directories of older versions (one digest of the whole core)
USER_CACHE_PREFIX = USER_CACHE_NAME + "-"
_OLD_USER_CACHE_NAME = re.compile(re.escape(USER_CACHE_PREFIX) + r"[0-9a-f]{16}")
#: another digest's directory in the user's ``NUMBA_CACHE_DIR`` is removed once nothing in
#: it has been written for this long [s] (a process of another version may be using it)
STALE_USER_CACHE_S = 86400.0
_MODULE_DIR = re.compile(r"(?P<module>[A-Za-z_][\w.]*)-(?P<digest>[0-9a-f]{16})")


def user_cache_dir(base) -> Path:
    """This package's cache directory inside ``base``, a ``NUMBA_CACHE_DIR`` set by the
    user (one subdirectory per module and digest in it)."""
    return Path(base) / USER_CACHE_NAME


def module_cache_dir(root: Path, rel: str, digest: str) -> Path:
    """The cache directory of the core module ``rel`` (relative path) at ``digest``."""
    return Path(root) / f"{_module_name(rel)}-{digest}"


def _last_written(directory: Path) -> float:
    """Newest modification time [s since the epoch] of ``directory`` and everything in it."""
    newest = directory.stat().st_mtime
    for root, dirs, files in os.walk(directory):
        for name in dirs + files:
            try:
                newest = max(newest, os.lstat(os.path.join(root, name)).st_mtime)
            except OSError:
                pass
    return newest


def _remove(directory: Path, stale_after: float | None, now: float) -> bool:
    """Remove ``directory`` (not a link to one) if, with ``stale_after`` [s], nothing has
    written to it for that long; True if it is gone."""
    try:
        if directory.is_symlink() or not directory.is_dir():
            return False
        if stale_after is not None and now - _last_written(directory) < stale_after:
            return False
    except OSError:
        return False
    shutil.rmtree(directory, ignore_errors=True)
    return not directory.exists()


def _remove_other_digests(
    root: Path, digests: dict[str, str], stale_after: float | None
) -> list[Path]:
    """Remove the module directories in ``root`` (``<module>-<digest>``) of a core module
    at another digest than ``digests``; in the package's own cache (``stale_after`` None)
    also those of a module the core no longer has (a version whose modules were named or
    placed otherwise). With ``stale_after`` [s] (a user's shared directory), only those
    nothing has written to for that long. Anything else in ``root`` is left alone. Returns
    the directories removed."""
    current = {_module_name(rel): d for rel, d in digests.items()}
    try:
        entries = list(root.iterdir())
    except OSError:
        return []
    now = time.time()
    removed = []
    for old in entries:
        m = _MODULE_DIR.fullmatch(old.name)
        if m is None:
            continue
        known = current.get(m["module"])
        if known == m["digest"] or (known is None and stale_after is not None):
            continue  # current; or, in a shared directory, a module this version lacks
        if _remove(old, stale_after, now):
            removed.append(old)
    return removed


def _writable(base: Path) -> bool:
    try:
        base.mkdir(parents=True, exist_ok=True)
        probe = base / f".write-test-{os.getpid()}"
        probe.touch()
        probe.unlink()
        return True
    except OSError:
        return False


def _cache_root() -> tuple[Path, float | None]:
    """The root of the core's cache (module directories in it) and after how long another
    digest's directory there may be removed (None: at once)."""
    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        return user_cache_dir(user), STALE_USER_CACHE_S
    for base in (PACKAGE / "__pycache__", Path.home() / ".cache" / "scoutsim"):
        if _writable(base):
            return base / "numba", None
    return PACKAGE / "__pycache__" / "numba", None


def _remove_old_layout(root: Path, stale_after: float | None) -> list[Path]:
    """Remove the whole-core cache directories of older versions (``numba-<digest>`` next
    to ``root``, or ``scoutsim-numba-<digest>`` in the user's directory once stale).
    Returns the directories removed."""
    base = root.parent
    pattern = _OLD_USER_CACHE_NAME if stale_after is not None else re.compile(r"numba-[0-9a-f]{16}")
    try:
        olds = [p for p in base.iterdir() if pattern.fullmatch(p.name)]
    except OSError:
        return []
    now = time.time()
    return [old for old in olds if _remove(old, stale_after, now)]


_ROOT, _STALE_AFTER = _cache_root()
_DIGESTS = module_digests(memo=_ROOT / "imports.json")
#: cache directory of each core source file (resolved path) of this package
_MODULE_DIRS = {str(PACKAGE / rel): module_cache_dir(_ROOT, rel, d) for rel, d in _DIGESTS.items()}


def install_cache_locator() -> str | None:
    """Put the cache of every function of a core module into that module's directory
    (:data:`_MODULE_DIRS`), with the module's digest as Numba's source stamp: a class put
    first in Numba's list of cache locators (``CacheImpl._locator_classes``, private).

    Harmless to other Numba users: the locator answers only for the core's own source
    files (a resolved path in :data:`_MODULE_DIRS`) and returns None for every other file,
    and Numba then asks its own locators as before; nothing else of Numba's caching is
    changed. Guarded: if Numba has no such list (another release), it is left as it is and the
    reason is returned (None: installed); :mod:`.jit` then compiles the core without the
    on-disk cache (Numba's own locators check only the timestamp of a function's own file,
    which would serve a stale callee after an edit of another module) and its ``status()``
    says why."""
    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    base = getattr(caching, "_CacheLocator", None)
    classes = getattr(impl, "_locator_classes", None)
    if not isinstance(base, type) or not isinstance(classes, list):
        return (
            "numba.core.caching has no CacheImpl._locator_classes list or _CacheLocator "
            "class; the core is not cached on disk"
        )

    class _CoreCacheLocator(base):  # type: ignore[valid-type,misc]  # (Numba's class, found above)
        def __init__(self, py_func, path: Path, digest: str, py_file: str = ""):
            self._lineno = py_func.__code__.co_firstlineno
            # (Numba names the source file when it warns that a function cannot be cached)
            self._py_file = py_file
            self._path = str(path)
            self._digest = digest

        def get_cache_path(self):
            return self._path

        def get_source_stamp(self):
            return self._digest

        def get_disambiguator(self):
            return str(self._lineno)

        @classmethod
        def from_function(cls, py_func, py_file):
            path = _MODULE_DIRS.get(os.path.realpath(py_file))
            if path is None:
                return None
            self = cls(py_func, path, path.name.rsplit("-", 1)[1], py_file)
            try:
                self.ensure_cache_path()
            except OSError:
                return None
            return self

    if not any(c.__name__ == "_CoreCacheLocator" for c in classes):
        classes.insert(0, _CoreCacheLocator)
    return None


def cache_directory() -> Path:
    """Root of the on-disk cache of the compiled core (one directory per module and digest
    in it)."""
    return _ROOT


def clean_cache() -> list[Path]:
    """Remove the cache directories of the core's modules at other digests than this
    package's (an older or newer version, an edited source) and the whole-core directories
    of older versions; in a user's ``NUMBA_CACHE_DIR`` only those of ours that nothing has
    written to for a day (:data:`STALE_USER_CACHE_S`). Returns the directories removed."""
    return _remove_other_digests(_ROOT, _DIGESTS, _STALE_AFTER) + _remove_old_layout(
        _ROOT, _STALE_AFTER
    )


def cache_size(root: Path | None = None) -> int:
    """Bytes in the files under ``root`` (default: :func:`cache_directory`)."""
    total = 0
    for base, _, files in os.walk(root or _ROOT):
        for name in files:
            try:
                total += os.lstat(os.path.join(base, name)).st_size
            except OSError:
                pass
    return total


_cleaned = False
_clean_lock = threading.Lock()


def clean_once():
    """:func:`clean_cache`, the first time the core compiles in this process."""
    global _cleaned
    with _clean_lock:
        if not _cleaned:
            _cleaned = True
            clean_cache()


def core_is_compiled() -> bool:
    """True if the compiled run loop (and with it the whole core it calls) is in the cache,
    i.e. a simulation will not have to compile first (this process may still load it)."""
    d = _MODULE_DIRS[str(PACKAGE / "_core" / "loop.py")]
    return d.is_dir() and any(d.glob("loop.run-*.nbi"))

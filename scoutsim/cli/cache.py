"""``scoutsim cache``: where the compiled core is cached on disk, how large the cache is and
whether the core is compiled; ``--clean`` removes the directories of other versions of the
core (in a ``NUMBA_CACHE_DIR`` of the user's, only stale ones of ours:
:func:`scoutsim._numba.disk_cache.clean_cache`).

    scoutsim cache [--clean]
"""

from __future__ import annotations

NAME = "cache"


def register(sub, common) -> None:
    c = sub.add_parser(
        NAME,
        help="where the compiled core is cached, its size; --clean removes old versions",
        description="Print the directory of the compiled core's on-disk cache, its size and "
        "whether the core is compiled. With --clean, first remove the cache "
        "directories of other versions of the core (an older install, an edited "
        "source); in a NUMBA_CACHE_DIR of yours only the directories of scoutsim's "
        "that nothing has written to for a day, nothing else.",
    )
    c.add_argument(
        "--clean",
        action="store_true",
        help="remove the cache directories of other versions of the core",
    )
    c.set_defaults(func=execute)


def _size_text(n_bytes: int) -> str:
    size = float(n_bytes)
    for unit in ("bytes", "kB", "MB", "GB"):
        if size < 1000.0 or unit == "GB":
            return f"{n_bytes} bytes" if unit == "bytes" else f"{size:.1f} {unit}"
        size /= 1000.0
    return f"{n_bytes} bytes"


def execute(args) -> int:
    from .._numba.disk_cache import cache_directory, cache_size, clean_cache, core_is_compiled

    if args.clean:
        removed = clean_cache()
        for path in removed:
            print(f"removed {path}")
        print(f"removed {len(removed)} director{'y' if len(removed) == 1 else 'ies'}")
    root = cache_directory()
    print(f"cache directory: {root}")
    print(f"size: {_size_text(cache_size(root))}")
    print(f"core compiled: {'yes' if core_is_compiled() else 'no (the next run compiles it)'}")
    return 0

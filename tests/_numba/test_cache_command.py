"""``scoutsim cache`` (scoutsim.cli.cache): it says where the compiled core is cached, how
large the cache is and whether the core is compiled; ``--clean`` removes only this
package's cache directories of other digests that are stale in a user's NUMBA_CACHE_DIR,
says which, and leaves everything else."""

import os
import re
import subprocess
import sys
import time

from scoutsim._numba import disk_cache


def _size_kb(stdout: str) -> float:
    return float(re.search(r"^size: ([0-9.]+) kB$", stdout, re.M).group(1))


def _bytes_under(root) -> int:
    return sum(f.stat().st_size for f in root.rglob("*") if f.is_file())


def test_cache_command_reports_and_cleans_only_stale_directories_of_ours(tmp_path):
    user = tmp_path / "user-cache"
    root = disk_cache.user_cache_dir(user)
    stale = root / f"_core.loop-{'0' * 16}"
    recent = root / f"_core.loop-{'1' * 16}"
    not_ours = user / "another_program"
    for d in (stale, recent, not_ours):
        d.mkdir(parents=True)
        (d / "f.nbi").write_bytes(b"x" * 1000)
    old = time.time() - 2 * disk_cache.STALE_USER_CACHE_S
    for path in (stale / "f.nbi", stale):
        os.utime(path, (old, old))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(user))
    p = subprocess.run(
        [sys.executable, "-m", "scoutsim", "cache"],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    assert f"cache directory: {root}" in p.stdout
    assert _size_kb(p.stdout) == round(_bytes_under(root) / 1000.0, 1)
    size_before = _size_kb(p.stdout)
    assert "core compiled: no" in p.stdout
    assert stale.exists()  # nothing removed unless asked
    p = subprocess.run(
        [sys.executable, "-m", "scoutsim", "cache", "--clean"],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    assert f"removed {stale}" in p.stdout and "removed 1 directory" in p.stdout
    assert not stale.exists()
    assert (recent / "f.nbi").exists() and (not_ours / "f.nbi").exists()
    assert _size_kb(p.stdout) == round(_bytes_under(root) / 1000.0, 1)
    assert abs(_size_kb(p.stdout) - (size_before - 1.0)) < 0.11  # the 1000 bytes removed

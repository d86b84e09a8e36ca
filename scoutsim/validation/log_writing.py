"""Writing experiment logs: :func:`save_log` (CSV with ``# key = value`` metadata lines,
gzip-compressed CSV with reproducible bytes, or Parquet with the metadata in the file's
key-value metadata), the format of :mod:`scoutsim.validation.log_format`.
"""

from __future__ import annotations

import gzip
import io
import json
from pathlib import Path

import numpy as np

from .log_format import LOG_SUFFIXES, PARQUET_META_KEY, log_suffix

__all__ = ["save_log"]

_FORMATS = {"t": "%.6f", "leg_state_back": "%d", "leg_state_front": "%d"}


def save_log(log, path, precision: int = 7) -> Path:
    """Write ``log`` (an :class:`~scoutsim.validation.experiment_log.ExperimentLog`) as CSV
    (``.csv``, ``.csv.gz``) with ``# key = value`` metadata lines, or as Parquet
    (``.parquet``/``.pq``, needs pyarrow)."""
    path = Path(path)
    suffix = log_suffix(path)
    meta = {k: v for k, v in log.meta.items()}
    names = list(log.columns)
    if suffix in (".parquet", ".pq"):
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise ImportError(
                "writing Parquet logs needs the optional dependency pyarrow; "
                "install it with `pip install pyarrow`"
            ) from None
        table = pa.table({n: log.columns[n] for n in names})
        table = table.replace_schema_metadata({PARQUET_META_KEY: json.dumps(meta).encode()})
        pq.write_table(table, path)
        return path
    if suffix not in (".csv", ".csv.gz"):
        raise ValueError(f"{path}: unknown log format; use {', '.join(LOG_SUFFIXES)}")
    buf = io.StringIO()
    for k, v in meta.items():
        buf.write(f"# {k} = {json.dumps(v)}\n")
    buf.write(",".join(names) + "\n")
    fmts = [_FORMATS.get(n, f"%.{precision}g") for n in names]
    data = np.column_stack([log.columns[n] for n in names])
    np.savetxt(buf, data, delimiter=",", fmt=fmts)
    text = buf.getvalue()
    if suffix == ".csv.gz":
        with gzip.GzipFile(path, "wb", mtime=0) as fh:  # mtime 0: reproducible bytes
            fh.write(text.encode("utf-8"))
    else:
        path.write_text(text, encoding="utf-8")
    return path

"""scoutsim.io.tables: named columns on disk, read back bit for bit in both formats."""

import gzip
import math

import numpy as np
import pytest

from scoutsim.io.tables import (
    FORMATS,
    TableError,
    TableWriter,
    read_metadata,
    read_table,
    write_table,
)

pytest.importorskip("pyarrow")


def _columns(n=7):
    rng = np.random.default_rng(3)
    x = rng.normal(size=n) * 10.0 ** rng.integers(-300, 300, size=n)
    x[:3] = [math.inf, -0.0, 5e-324]  # extremes that must survive
    y = rng.normal(size=n)
    y[1] = math.nan
    return {
        "t": np.arange(n) * 1e-3,
        "x": x,
        "y": y,
        "code": np.arange(n, dtype=np.int8) - 3,
        "bits": (np.arange(n, dtype=np.int32) * 1000003),
        "name": np.array([f"kind_{i}" for i in range(n)]),
    }


@pytest.mark.parametrize("fmt", FORMATS)
def test_round_trip_is_bit_exact_with_dtypes_units_and_metadata(tmp_path, fmt):
    cols = _columns()
    meta = {"outcome": "completed", "stats": {"a": 1.5, "b": math.nan}}
    path = write_table(tmp_path / "table", cols, units={"t": "s", "x": "m"}, metadata=meta, fmt=fmt)
    assert path.name == "table" + {"parquet": ".parquet", "csv": ".csv.gz"}[fmt]
    back, meta_back = read_table(path)
    assert list(back) == list(cols)
    for n, c in cols.items():
        assert back[n].dtype == c.dtype, n
        if c.dtype.kind == "f":
            np.testing.assert_array_equal(back[n].view(np.int64), c.view(np.int64), err_msg=n)
        else:
            np.testing.assert_array_equal(back[n], c, err_msg=n)
    assert meta_back["outcome"] == "completed" and math.isnan(meta_back["stats"]["b"])
    info = read_metadata(path)
    assert info["columns"]["t"]["unit"] == "s" and info["columns"]["code"]["unit"] is None
    assert not list(tmp_path.glob("*.partial"))


@pytest.mark.parametrize("fmt", FORMATS)
def test_empty_table(tmp_path, fmt):
    cols = {"t": np.zeros(0), "kind": np.zeros(0, dtype=np.int8)}
    back, _ = read_table(write_table(tmp_path / "e", cols, fmt=fmt))
    assert back["t"].shape == (0,) and back["kind"].dtype == np.int8


def test_csv_header_names_units(tmp_path):
    path = write_table(
        tmp_path / "c", {"t": np.zeros(2), "n": np.ones(2, np.int8)}, units={"t": "s"}, fmt="csv"
    )
    with gzip.open(path, "rt") as f:
        lines = f.read().splitlines()
    assert lines[0].startswith("# scoutsim: ") and lines[1] == "t [s],n"
    assert lines[2] == "0,1"


def test_bad_inputs(tmp_path):
    with pytest.raises(ValueError, match="format 'xls' is not allowed"):
        write_table(tmp_path / "x", {"t": np.zeros(1)}, fmt="xls")
    with pytest.raises(ValueError, match="unequal length"):
        write_table(tmp_path / "x", {"t": np.zeros(1), "u": np.zeros(2)})
    foreign = tmp_path / "foreign.csv.gz"
    with gzip.open(foreign, "wt") as f:
        f.write("a,b\n1,2\n")
    with pytest.raises(TableError, match="not a table written by scoutsim"):
        read_table(foreign)
    with pytest.raises(TableError, match="not a table file"):
        read_table(tmp_path / "x.txt")
    (tmp_path / "broken.parquet").write_bytes(b"not parquet")
    with pytest.raises(TableError, match="cannot read"):
        read_table(tmp_path / "broken.parquet")


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_table_written_in_pieces_reads_back_as_the_whole(tmp_path, fmt, monkeypatch):
    """TableWriter (streamed runs): rows appended in uneven pieces, several Parquet row
    groups, metadata added at the end: read_table gives what write_table of the whole
    gives, bit for bit."""
    monkeypatch.setattr(TableWriter, "ROW_GROUP_ROWS", 10)
    cols = _columns(57)
    meta = {"outcome": "fell", "t_end": 1.25}
    w = TableWriter(tmp_path / "piecewise", units={"t": "s"}, fmt=fmt)
    for a, b in ((0, 1), (1, 23), (23, 23), (23, 57)):
        w.append({n: c[a:b] for n, c in cols.items()})
        assert not w.path.exists()  # nothing looks whole before close()
    path = w.close(metadata=meta)
    whole, meta_whole = read_table(
        write_table(tmp_path / "whole", cols, units={"t": "s"}, metadata=meta, fmt=fmt)
    )
    back, meta_back = read_table(path)
    assert meta_back == meta_whole and read_metadata(path) == read_metadata(
        tmp_path / ("whole" + path.name[len("piecewise") :])
    )
    for n in cols:
        assert back[n].dtype == whole[n].dtype, n
        assert back[n].tobytes() == whole[n].tobytes(), n
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [path.name, "whole" + path.name[len("piecewise") :]]
    )
    if fmt == "parquet":
        import pyarrow.parquet as pq

        assert pq.ParquetFile(path).metadata.num_row_groups == 2  # rows 0-22, 23-56


@pytest.mark.parametrize("fmt", FORMATS)
def test_an_aborted_or_inconsistent_piecewise_table_leaves_nothing(tmp_path, fmt):
    cols = _columns(5)
    w = TableWriter(tmp_path / "cut", fmt=fmt)
    w.append(cols)
    with pytest.raises(ValueError, match="differ from the first"):
        w.append({"t": cols["t"]})
    w.abort()
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match="no rows were appended"):
        TableWriter(tmp_path / "none", fmt=fmt).close()

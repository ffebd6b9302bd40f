"""Large studies: rows streamed to the output, tasks sized from memory, K(ω) curves."""

import json
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc.errors import MechcircError
from mechcirc.study import journal_path, parse_spec, run_study
from mechcirc.study.executors import TASK_BYTES, task_size
from mechcirc.study.journal import _journal_in_order

NET = ".param m=2\nmass m1 a 0 m\nspring k a 0 100\ndamper c a 0 3\ndrive V a 0 velocity=1\n"


def spec_of(tmp_path, values, analysis="sweep"):
    net = tmp_path / "n.mcir"
    net.write_text(NET)
    data = {"netlist": str(net), "analysis": analysis, "grid": {"m": values}}
    if analysis == "sweep":
        data["omega"] = {"min": 1, "max": 30, "points": 7, "log": True}
    return parse_spec(data, source="t.toml")


def test_streamed_table_is_the_table_held_in_memory(tmp_path):
    # keep_rows=False keeps only the failed rows; the file is the same, written from
    # the journal (tasks finishing out of order on two processes).
    spec = spec_of(tmp_path, [1.0, -1.0, 2.0, 3.0, 0.5, 4.0])
    held = run_study(spec, output=tmp_path / "held.csv", workers=1)
    streamed = run_study(spec, output=tmp_path / "streamed.csv", workers=2, batch_size=1,
                         keep_rows=False)
    assert (tmp_path / "held.csv").read_bytes() == (tmp_path / "streamed.csv").read_bytes()
    assert streamed.count == held.count == 6 and streamed.failed == held.failed == 1
    assert [r["index"] for r in streamed.rows] == [1]
    assert not Path(journal_path(tmp_path / "streamed.csv")).exists()


def test_parquet_table_holds_the_csv_tables_cells(tmp_path):
    # The Parquet table is parsed from the journal's lines by pyarrow; the CSV
    # table, read back here by the csv module, is the reference: the same numbers
    # (bit for bit), the same error text (a quoted cell: it has a comma), nulls
    # where the CSV has empty cells.
    import csv

    pq = pytest.importorskip("pyarrow.parquet", reason="pyarrow is not installed")
    spec = spec_of(tmp_path, [1.0, -1.0, 2.0, 3.0])
    run_study(spec, output=tmp_path / "t.csv", workers=1)
    run_study(spec, output=tmp_path / "t.parquet", workers=2, batch_size=1, keep_rows=False)
    with open(tmp_path / "t.csv", newline="", encoding="utf-8") as fh:
        head, *rows = list(csv.reader(fh))
    table = pq.read_table(tmp_path / "t.parquet").to_pydict()
    assert list(table) == head and len(rows) == 4
    assert "," in rows[1][head.index("error")]
    for k, name in enumerate(head):
        for r, row in enumerate(rows):
            want = (None if row[k] == "" else row[k] if name in ("status", "error") else
                    int(row[k]) if name in ("index", "n_flagged") else float(row[k]))
            got = table[name][r]
            if isinstance(want, float):
                assert got == want or (np.isnan(got) and np.isnan(want)), (name, r)
            else:
                assert got == want, (name, r)


def test_journal_read_back_in_index_order_chunk_by_chunk(tmp_path):
    # The journal's rows in the order tasks finished, one of them twice: read back
    # sorted by index, the first copy kept, in chunks of 2.
    spec = spec_of(tmp_path, [1.0, 2.0, 3.0, 4.0, 5.0])
    out = tmp_path / "r.csv"
    seen = []

    def stop(n):
        seen.append(n)
        if len(seen) == 5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study(spec, output=out, workers=1, batch_size=1, on_rows=stop)
    journal = journal_path(out)
    lines = Path(journal).read_bytes().splitlines(keepends=True)
    head, rows = lines[:2], lines[2:]
    assert len(rows) == 5
    shuffled = [rows[3], rows[0], rows[4], rows[1], rows[0], rows[2]]
    Path(journal).write_bytes(b"".join(head + shuffled))
    chunks = list(_journal_in_order(journal, len(spec.columns), chunk=2))
    assert [len(c) for c in chunks] == [2, 2, 1]
    got = [r for c in chunks for r in c]
    assert [r.split(b",")[0] for r in got] == [b"0", b"1", b"2", b"3", b"4"]
    assert got[0] == rows[0].rsplit(b",", 1)[0] + b"\r\n"     # the CSV row, no checksum


def test_damaged_journal_row_is_an_error_not_a_wrong_table(tmp_path):
    spec = spec_of(tmp_path, [1.0, 2.0])
    out = tmp_path / "r.csv"
    with pytest.raises(KeyboardInterrupt):
        run_study(spec, output=out, workers=1, batch_size=1,
                  on_rows=lambda n: (_ for _ in ()).throw(KeyboardInterrupt))
    journal = journal_path(out)
    text = Path(journal).read_bytes().replace(b",ok,", b",ko,", 1)
    Path(journal).write_bytes(text)
    with pytest.raises(MechcircError, match="changed on disk"):
        list(_journal_in_order(journal, len(spec.columns)))


def test_task_size_follows_memory_and_the_workers(tmp_path):
    spec = spec_of(tmp_path, [1.0])                  # 7 ω points
    per = 13_000 + 40 * 7
    assert task_size(spec, 10**6, 2) == TASK_BYTES // per       # memory-bound
    assert task_size(spec, 1000, 2) == 125                       # four tasks per worker
    assert task_size(spec, 3, 8) == 1
    assert task_size(spec, 10**6, 2, batch_size=17) == 17
    res = spec_of(tmp_path, [1.0], analysis="resonances")
    assert task_size(res, 10**6, 1) == TASK_BYTES // 13_000


def test_curves_in_long_format_equal_each_point_alone(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet", reason="pyarrow is not installed")
    spec = spec_of(tmp_path, [1.0, -1.0, 2.0, 3.0])
    curves = tmp_path / "K.parquet"
    result = run_study(spec, workers=2, batch_size=1, curves=curves)
    assert [r["status"] for r in result.rows] == ["ok", "error", "ok", "ok"]
    table = pq.read_table(curves)
    assert table.column_names == ["design", "omega", "K_re", "K_im"]
    units = {f.name: (f.metadata or {}).get(b"unit") for f in table.schema}
    assert units == {"design": None, "omega": b"rad/s", "K_re": b"m/(N\xc2\xb7s)",
                     "K_im": b"m/(N\xc2\xb7s)"}
    record = json.loads(table.schema.metadata[b"mechcirc"])
    assert record["spec_sha256"] == spec.sha256 and "long format" in record["curves"]
    t = table.to_pydict()
    assert len(t["design"]) == 3 * 7 and 1 not in t["design"]     # the failed point: none
    omega = np.geomspace(1, 30, 7)
    for d, m in ((0, 1.0), (2, 2.0), (3, 3.0)):
        sel = np.array(t["design"]) == d
        np.testing.assert_array_equal(np.array(t["omega"])[sel], omega)
        K = np.array(t["K_re"])[sel] + 1j * np.array(t["K_im"])[sel]
        # The point alone (mechcirc.parse + sweep), and the closed form of this
        # network: K = 1/(jωm + k/(jω) + c).
        single = mechcirc.parse(NET, params={"m": m}).sweep(omega).K
        np.testing.assert_allclose(K, single, rtol=1e-13, atol=0)
        closed = 1 / (1j * omega * m + 100 / (1j * omega) + 3)
        np.testing.assert_allclose(K, closed, rtol=1e-13, atol=0)


def test_curves_are_refused_where_they_cannot_be_made(tmp_path):
    pytest.importorskip("pyarrow", reason="pyarrow is not installed")
    with pytest.raises(MechcircError, match="need analysis"):
        run_study(spec_of(tmp_path, [1.0], analysis="resonances"), workers=1,
                  curves=tmp_path / "K.parquet")
    with pytest.raises(MechcircError, match="cannot be resumed"):
        run_study(spec_of(tmp_path, [1.0]), output=tmp_path / "r.csv", workers=1,
                  resume=True, curves=tmp_path / "K.parquet")
    assert not (tmp_path / "K.parquet").exists() and not (tmp_path / "r.csv").exists()

"""The campaign matrix: same seeds, same results on every backend; streamed, resumable."""

import json

import pytest

from bushenv.execution import LocalBackend
from bushenv.progress import Progress
from bushenv.search.matrix import (
    MatrixError,
    comparable,
    make_cells,
    parse_seeds,
    read_results,
    run_matrix,
    summarise,
)

CELLS = make_cells(["linear"], ["axial"], ["random", "cma"], [0, 1], budget=32)


def test_parse_seeds_ranges_lists_and_errors():
    assert parse_seeds("0-3") == [0, 1, 2, 3]
    assert parse_seeds("1,4,7") == [1, 4, 7]
    with pytest.raises(MatrixError, match="runs backwards"):
        parse_seeds("5-2")
    with pytest.raises(MatrixError, match="expected e.g. 0-9"):
        parse_seeds("a-b")


def test_local_pool_gives_the_same_rows_as_in_process(tmp_path):
    with LocalBackend(workers=1) as one:
        serial = run_matrix(CELLS, tmp_path / "one", one, progress=Progress(quiet=True))
    with LocalBackend(workers=2) as two:
        pooled = run_matrix(CELLS, tmp_path / "two", two, progress=Progress(quiet=True))
    assert [comparable(r) for r in serial] == [comparable(r) for r in pooled]
    # the linear control is never flagged, whatever the searcher finds
    assert not any(r["diverged"] for r in serial)
    table = summarise(serial)
    assert table["linear"]["random"]["runs"] == 2
    assert table["linear"]["random"]["divergence_rate"] == 0.0


def test_interrupted_matrix_resumes_and_drops_a_torn_line(tmp_path):
    out = tmp_path / "m"
    with LocalBackend(workers=1) as one:
        run_matrix(CELLS[:2], out, one, progress=Progress(quiet=True))
        path = out / "cells.jsonl"
        with path.open("a") as fh:
            fh.write('{"model": "linear", "axis": "ax')  # killed mid-write
        with pytest.raises(MatrixError, match="exists; pass --resume"):
            run_matrix(CELLS, out, one, progress=Progress(quiet=True))
        msgs = []
        rows = run_matrix(CELLS, out, one, resume=True, progress=Progress(sink=msgs.append))
    assert "interrupted write" in msgs[0] and "2 already done, 2 to run" in msgs[1]
    assert len(rows) == 4
    assert len(read_results(out / "cells.jsonl")) == 4


def test_corrupt_line_in_the_middle_is_refused_naming_the_line(tmp_path):
    path = tmp_path / "cells.jsonl"
    good = json.dumps({k: CELLS[0][k] for k in CELLS[0]})
    path.write_text(good + "\nnot json\n" + good + "\n")
    with pytest.raises(MatrixError, match="line 2: corrupt"):
        read_results(path)


def test_ray_backend_gives_identical_results_to_local(tmp_path):
    ray = pytest.importorskip("ray", reason="Ray not installed (pip install 'bushenv[ray]')")
    from bushenv.execution import RayBackend

    with LocalBackend(workers=1) as one:
        local = run_matrix(CELLS, tmp_path / "local", one, progress=Progress(quiet=True))
    backend = RayBackend(num_cpus=2)
    try:
        remote = run_matrix(CELLS, tmp_path / "ray", backend, progress=Progress(quiet=True))
    finally:
        backend.close()
    assert not ray.is_initialized()
    assert [comparable(r) for r in local] == [comparable(r) for r in remote]


def test_cells_are_judged_against_the_reference_they_name(tmp_path):
    from bushenv.models.linear import LinearBushing
    from bushenv.search.matrix import make_cells, run_cell

    ref = LinearBushing.preset("axial").save(tmp_path / "ref.npz")
    free, own = (
        run_cell(make_cells(["linear"], ["axial"], ["random"], [0], 16, reference=r)[0])
        for r in (None, str(ref))
    )
    assert free["reference"] is None and own["reference"] == str(ref)
    assert not free["diverged"] and not own["diverged"]
    # the linear model judged against itself: the deviation it can reach is zero
    assert own["worst_deviation"] == 0.0

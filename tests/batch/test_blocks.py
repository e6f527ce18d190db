"""The rows a task of one huge capture on Dask reads (batch/_blocks.py): where workers find the
capture, and the line a worker that cannot see it gives."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from distributed import Client

from rotacal.batch._blocks import CaptureRows
from rotacal.errors import CaptureError


def test_a_relative_path_travels_as_an_absolute_one(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # a running scheduler's workers were started in folders of their own: "cap.npz" given in
    # this folder must not be looked for in theirs
    np.savez(tmp_path / "cap.npz", a=np.arange(5.0))
    monkeypatch.chdir(tmp_path)
    rows = CaptureRows("cap.npz", ("a",))
    assert rows.path == str(tmp_path / "cap.npz")
    monkeypatch.chdir(tmp_path.parent)
    assert rows.read(1, 3)["a"].tolist() == [1.0, 2.0]


def test_a_worker_that_cannot_see_the_capture_names_itself(
    dask_client: Client, tmp_path: Path
) -> None:
    np.savez(tmp_path / "cap.npz", a=np.arange(5.0))
    rows = CaptureRows(str(tmp_path / "cap.npz"), ("a",))
    (tmp_path / "cap.npz").unlink()  # as if the worker ran on a machine without this folder
    worker = next(iter(dask_client.scheduler_info()["workers"]))
    for task in (lambda r: r.read(0, 2), lambda r: list(r.chunks(["a"], 2))):
        future = dask_client.submit(task, rows, workers=[worker], pure=False)
        with pytest.raises(CaptureError) as caught:
            future.result()
        message = str(caught.value)
        assert message.startswith(f"Dask worker {worker} cannot see the capture {rows.path}")
        assert "same path (a shared file system)" in message
    with pytest.raises(CaptureError, match="this process cannot see the capture"):
        rows.read(0, 2)

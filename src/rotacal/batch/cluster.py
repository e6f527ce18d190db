"""The Dask cluster a batch or a huge capture runs on: a new local one, or a running one."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from typing import TYPE_CHECKING

from rotacal.errors import ConfigError

if TYPE_CHECKING:
    from distributed import Client

__all__ = ["dashboard_link", "dask_client"]


@contextlib.contextmanager
def dask_client(
    workers: int | None, scheduler: str | None, client: Client | None
) -> Iterator[Client]:
    """The Dask client: the one given, one connected to ``scheduler``, or one on a new local
    cluster of ``workers`` single-threaded processes (closed at the end)."""
    if client is not None:
        yield client
        return
    import logging

    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            remote = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as e:
            raise ConfigError(f"--scheduler {scheduler}: cannot connect ({e})") from None
        with remote:
            yield remote
        return
    import dask

    # Dask starts its workers with MALLOC_TRIM_THRESHOLD_=65536 (to hand freed memory back to the
    # system at once); that fixes glibc's thresholds, so every large NumPy temporary is a fresh
    # mapping and its pages fault in again: a plan took 570 ms instead of 450 ms. The workers
    # here keep glibc's adaptive defaults (memory stays bounded by the analyses themselves).
    environ = {
        k: v
        for k, v in dask.config.get("distributed.nanny.pre-spawn-environ", {}).items()
        if k != "MALLOC_TRIM_THRESHOLD_"
    }
    with (
        dask.config.set({"distributed.nanny.pre-spawn-environ": environ}),
        LocalCluster(
            n_workers=workers or os.cpu_count() or 1,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",  # a free port: batches side by side never collide
            silence_logs=logging.ERROR,
        ) as cluster,
        Client(cluster) as local,
    ):
        yield local


def dashboard_link(client: Client, local: bool) -> str | None:
    """The link to the cluster's dashboard, when it has one: Dask serves its pages only with
    bokeh installed (not a dependency of rotacal; ``pip install bokeh`` for the dashboard)."""
    import importlib.util

    if local and importlib.util.find_spec("bokeh") is None:
        return None
    if not client.scheduler_info().get("services", {}).get("dashboard"):
        return None
    return str(client.dashboard_link)

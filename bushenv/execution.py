"""Where evaluation batches and search runs execute: local processes (default) or a Ray cluster.

Searchers and campaigns call ``backend.map(fn, items)`` and get results in item order; they do
not know which backend runs them. ``fn`` must be a module-level function (picklable) and pure
given its item (seeds travel inside the items), so every backend returns identical results.

- ``LocalBackend(workers)``: ``workers == 1`` runs in this process (no pickling, no start-up);
  otherwise a ``ProcessPoolExecutor`` over the local cores.
- ``RayBackend(address=None, num_cpus=None)``: ``ray.init`` on an existing cluster
  (``address``, e.g. ``"auto"`` or ``"ray://head:10001"``) or a local instance; needs
  ``pip install bushenv[ray]``.

``imap_unordered`` streams ``(index, result)`` pairs as they finish, so a caller can write each
result to disk at once and an interrupted run loses nothing already finished.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any

from bushenv.errors import BadInput


class BackendError(BadInput):
    """A backend cannot start (Ray missing, cluster unreachable, bad worker count)."""


def local_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - non-Linux
        return os.cpu_count() or 1


def _die_with_parent() -> None:
    """Worker initialiser: on Linux, ask the kernel to SIGTERM this worker when its parent dies.

    Without it a ``kill -9`` of a campaign leaves its pool workers behind for good: each one
    waits on a task pipe whose write end its siblings still hold, so it never sees EOF.
    """
    try:
        import ctypes
        import signal

        # A SIGTERM handler inherited from the parent (bushenv.cli installs one) would turn the
        # kernel's signal into an exception the pool worker survives: restore the default.
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGTERM)
        if os.getppid() == 1:  # the parent died before prctl took effect
            os._exit(1)
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        pass


class LocalBackend:
    name = "local"

    def __init__(self, workers: int | None = None) -> None:
        workers = local_cores() if workers is None else int(workers)
        if workers < 1:
            raise BackendError(f"workers must be >= 1, got {workers}")
        self.workers = workers
        self._pool: ProcessPoolExecutor | None = None

    def _executor(self) -> ProcessPoolExecutor:
        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=self.workers, initializer=_die_with_parent)
        return self._pool

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> list[Any]:
        out: list[Any] = [None] * len(items)
        for i, result in self.imap_unordered(fn, items):
            out[i] = result
        return out

    def imap_unordered(
        self, fn: Callable[[Any], Any], items: Iterable[Any]
    ) -> Iterator[tuple[int, Any]]:
        items = list(items)
        if self.workers == 1 or len(items) <= 1:
            for i, item in enumerate(items):
                yield i, fn(item)
            return
        pool = self._executor()
        pending = {pool.submit(fn, item): i for i, item in enumerate(items)}
        try:
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in done:
                    yield pending.pop(fut), fut.result()
        finally:
            for fut in pending:
                fut.cancel()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def abort(self) -> None:
        """Stop at once: cancel queued items and end the worker processes (their running items
        are lost; whatever the caller already wrote stays)."""
        if self._pool is None:
            return
        pool, self._pool = self._pool, None
        # ProcessPoolExecutor has no public kill: without it an interrupted campaign would
        # wait for every running cell to finish, which can take minutes.
        workers = list(getattr(pool, "_processes", {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in workers:
            if proc.is_alive():
                proc.terminate()
        for proc in workers:
            proc.join(timeout=2)
            if proc.is_alive():
                # A worker that cannot run Python (e.g. stuck on a lock inherited through fork)
                # never acts on SIGTERM; SIGKILL needs no cooperation.
                proc.kill()
                proc.join(timeout=5)

    def __enter__(self) -> LocalBackend:
        return self

    def __exit__(self, exc_type: object, *exc: object) -> None:
        if exc_type is not None and issubclass(exc_type, KeyboardInterrupt):  # type: ignore[arg-type]
            self.abort()
        else:
            self.close()


class RayBackend:
    name = "ray"

    def __init__(self, address: str | None = None, num_cpus: int | None = None) -> None:
        try:
            import ray
        except ImportError:
            raise BackendError("the Ray backend needs Ray: pip install 'bushenv[ray]'") from None
        self._ray = ray
        self._started_here = False
        if not ray.is_initialized():
            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
            if address:
                kwargs["address"] = address
            else:
                kwargs["num_cpus"] = num_cpus or local_cores()
            try:
                ray.init(**kwargs)
            except Exception as exc:  # ray raises many types; say which cluster failed
                raise BackendError(
                    f"cannot start or reach Ray ({address or 'local'}): {exc}"
                ) from None
            self._started_here = True
        self.workers = int(ray.cluster_resources().get("CPU", 1))
        self._remote_cache: dict[Callable, Any] = {}

    def _remote(self, fn: Callable[[Any], Any]) -> Any:
        if fn not in self._remote_cache:
            self._remote_cache[fn] = self._ray.remote(fn)
        return self._remote_cache[fn]

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> list[Any]:
        out: list[Any] = [None] * len(items)
        for i, result in self.imap_unordered(fn, items):
            out[i] = result
        return out

    def imap_unordered(
        self, fn: Callable[[Any], Any], items: Iterable[Any]
    ) -> Iterator[tuple[int, Any]]:
        remote = self._remote(fn)
        refs = {remote.remote(item): i for i, item in enumerate(items)}
        try:
            while refs:
                done, _ = self._ray.wait(list(refs), num_returns=1)
                for ref in done:
                    yield refs.pop(ref), self._ray.get(ref)
        finally:
            for ref in refs:
                self._ray.cancel(ref)

    def close(self) -> None:
        if self._started_here and self._ray.is_initialized():
            self._ray.shutdown()

    def __enter__(self) -> RayBackend:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def get_backend(
    name: str = "local", workers: int | None = None, address: str | None = None
) -> LocalBackend | RayBackend:
    """``"local"`` or ``"ray"``; ``address`` implies Ray."""
    if address or name == "ray":
        return RayBackend(address=address, num_cpus=workers)
    if name == "local":
        return LocalBackend(workers)
    raise BackendError(f"unknown backend {name!r}; choose 'local' or 'ray'")

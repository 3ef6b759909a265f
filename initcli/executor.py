"""Where independent tasks run: this machine's process pool, or a Ray cluster.

An :class:`Executor` is a small protocol -- ``submit(fn, *args)`` returns a handle, ``wait_any``
returns the handles that finished, ``result`` their value -- so that the evaluation campaign and
the survey share one scheduling loop (:func:`map_unordered`, a bounded window of tasks in flight,
results in completion order) whatever runs them. ``ray`` is optional (``pip install
bim-init[cluster]``); ``ray.init()`` with no address starts a local instance, ``address="auto"``
joins the cluster this machine belongs to, ``ray://host:10001`` a remote one.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal
import socket
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from typing import Any, Protocol

from bimkit.cli import EXIT_INTERRUPTED, EXIT_TERMINATED, error_line, native_stderr_silenced
from bimkit.errors import EXIT_BAD_INPUT, InputError

__all__ = [
    "EXECUTORS",
    "Executor",
    "LocalExecutor",
    "RayExecutor",
    "default_workers",
    "init_worker",
    "make_executor",
    "map_unordered",
]

EXECUTORS = ("local", "ray")
PROBE_TIMEOUT_S = 5.0  # s: a TCP connection to the Ray address
CONNECT_TIMEOUT_S = 20.0  # s: ray.init on an address that accepts connections (both within 30 s)
MANAGER_JOIN_S = 10.0  # s: the pool's manager thread, once its workers are gone


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)


def init_worker() -> None:
    """One thread per worker process: the tasks are the parallelism."""
    try:
        import cv2

        cv2.setNumThreads(1)
    except ImportError:  # pragma: no cover - opencv is a core dependency
        pass


class Executor(Protocol):
    slots: int  # tasks that run at once

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any: ...

    def wait_any(self, handles: set[Any]) -> tuple[set[Any], set[Any]]: ...

    def result(self, handle: Any) -> Any: ...

    def close(self, cancel: bool = False) -> None: ...


class _Done:
    """A result computed in this process."""

    def __init__(self, value: Any) -> None:
        self.value = value


class LocalExecutor:
    """``workers`` spawned processes (1: run in this process, no pool)."""

    def __init__(self, workers: int = 1, initializer: Callable[[], None] | None = init_worker) -> None:
        self.slots = max(1, workers)
        self._pool: ProcessPoolExecutor | None = None
        if self.slots > 1:
            # spawn, not fork: the parent runs a progress-bar thread, and forking a process with
            # threads can deadlock the children on a lock held at fork time.
            context = multiprocessing.get_context("spawn")
            self._pool = ProcessPoolExecutor(
                max_workers=self.slots, initializer=initializer, mp_context=context
            )
        elif initializer is not None:
            initializer()

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future | _Done:
        if self._pool is None:
            return _Done(fn(*args))
        return self._pool.submit(fn, *args)

    def wait_any(self, handles: set[Any]) -> tuple[set[Any], set[Any]]:
        done = {h for h in handles if isinstance(h, _Done)}
        if done:
            return done, handles - done
        finished, pending = wait(handles, return_when=FIRST_COMPLETED)
        return set(finished), set(pending)

    def result(self, handle: Any) -> Any:
        return handle.value if isinstance(handle, _Done) else handle.result()

    def close(self, cancel: bool = False) -> None:
        """Wait for the running tasks, or with ``cancel`` (an interrupt) stop the workers at once."""
        if self._pool is None:
            return
        pool, self._pool = self._pool, None
        if not cancel:
            pool.shutdown(wait=True)
            return
        # No public way to stop them: take the workers and the pool's manager thread before
        # shutdown(), which drops its references to both.
        processes = list(getattr(pool, "_processes", {}).values())
        manager = getattr(pool, "_executor_manager_thread", None)
        pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()
        for process in processes:
            process.join(timeout=5)
            if process.is_alive():
                process.kill()
                process.join(timeout=5)
        # Let the manager thread see its workers gone (it fails their futures) and close its
        # wake-up pipe now: left to the interpreter's exit, the exit hook may write to that pipe as
        # the thread closes it (Python 3.11: "Exception ignored ... Bad file descriptor").
        if manager is not None:
            manager.join(timeout=MANAGER_JOIN_S)


class RayExecutor:
    """Tasks on a Ray cluster: ``address`` None starts a local instance (``num_cpus`` of them)."""

    def __init__(self, address: str | None = None, num_cpus: int | None = None) -> None:
        try:
            import ray
        except ImportError:
            raise InputError(
                "--executor ray needs the ray package: pip install 'bim-init[cluster]' (or pip install ray)"
            ) from None
        self._ray = ray
        self._owned = not ray.is_initialized()
        if self._owned:
            kwargs: dict[str, Any] = {
                "include_dashboard": False,
                "log_to_driver": False,
                "logging_level": logging.ERROR,
            }
            if address is None:
                kwargs["num_cpus"] = num_cpus
            else:
                probe_address(address)
            ours = signal.getsignal(signal.SIGTERM)  # ray.init puts its own handler in
            try:
                with _deadline(address, CONNECT_TIMEOUT_S if address is not None else None):
                    ray.init(address=address, **kwargs)
            except (ConnectionError, RuntimeError, ValueError) as exc:
                first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
                raise InputError(
                    f"--address {address}: cannot connect to the Ray cluster ({first})"
                ) from None
            finally:
                if threading.current_thread() is threading.main_thread():
                    signal.signal(signal.SIGTERM, ours)
        self.slots = max(1, int(ray.cluster_resources().get("CPU", 1)))
        self._remote: dict[Callable[..., Any], Any] = {}

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any:
        remote = self._remote.get(fn)
        if remote is None:
            remote = self._remote[fn] = self._ray.remote(num_cpus=1)(_ray_task).options(name=fn.__name__)
        return remote.remote(fn, *args)

    def wait_any(self, handles: set[Any]) -> tuple[set[Any], set[Any]]:
        ready, _ = self._ray.wait(list(handles), num_returns=1)
        done = set(ready)
        return done, handles - done

    def result(self, handle: Any) -> Any:
        return self._ray.get(handle)

    def close(self, cancel: bool = False) -> None:
        if self._owned and self._ray.is_initialized():
            self._ray.shutdown()


def probe_address(address: str) -> None:
    """A Ray address (``host:port``, ``ray://host:port``; ``auto`` is left to Ray) that accepts a TCP
    connection within :data:`PROBE_TIMEOUT_S`; else one :class:`InputError` (``ray.init`` would
    retry for minutes)."""
    if address in ("auto", "local"):
        return
    text = address.split("://", 1)[1] if "://" in address else address
    host, sep, port = text.rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise InputError(f"--address {address}: expected host:port, ray://host:port or auto")
    try:
        socket.create_connection((host, int(port)), timeout=PROBE_TIMEOUT_S).close()
    except OSError as exc:
        why = "no answer" if isinstance(exc, TimeoutError) else exc.strerror or type(exc).__name__
        raise InputError(f"--address {address}: no Ray cluster answers there ({why})") from None


@contextmanager
def _deadline(address: str | None, seconds: float | None) -> Iterator[None]:
    """While ``ray.init`` blocks in native code (where Python's signal handlers cannot run), a watcher
    thread ends the process with one line when ``seconds`` pass (exit 2), or at once on SIGTERM
    (143) or Ctrl-C (130): the signals reach it through :func:`signal.set_wakeup_fd`. Nothing is
    written before the cluster is joined, so there is nothing to clean up. What Ray's core prints
    while it tries (its own retries and warnings) goes to /dev/null: the one line is ours."""
    if seconds is None or threading.current_thread() is not threading.main_thread():
        yield
        return
    with native_stderr_silenced() as stderr, _watched(address, seconds, stderr):
        yield


@contextmanager
def _watched(address: str | None, seconds: float, stderr: int) -> Iterator[None]:
    receiver, sender = socket.socketpair()
    sender.setblocking(False)
    previous = signal.set_wakeup_fd(sender.fileno(), warn_on_full_buffer=False)
    finished = threading.Event()

    def watch() -> None:
        receiver.settimeout(0.1)
        until = time.monotonic() + seconds
        while not finished.is_set():
            try:
                got = receiver.recv(64)
            except (TimeoutError, OSError):
                got = b""
            if finished.is_set():
                return
            if signal.SIGTERM in got or signal.SIGINT in got:
                code = EXIT_TERMINATED if signal.SIGTERM in got else EXIT_INTERRUPTED
                word = "terminated" if code == EXIT_TERMINATED else "interrupted"
                _exit_now(stderr, f"bim-init: {word}", code)
            if time.monotonic() > until:
                message = f"--address {address}: the Ray cluster did not answer within {seconds:.0f} s"
                _exit_now(stderr, error_line("bim-init", message), EXIT_BAD_INPUT)

    watcher = threading.Thread(target=watch, name="ray-connect-deadline", daemon=True)
    watcher.start()
    try:
        yield
    finally:
        finished.set()
        signal.set_wakeup_fd(previous)
        watcher.join(timeout=1)
        receiver.close()
        sender.close()


def _exit_now(fd: int, line: str, code: int) -> None:
    os.write(fd, (line + "\n").encode("utf-8", "backslashreplace"))
    os._exit(code)


def _ray_task(fn: Callable[..., Any], *args: Any) -> Any:
    init_worker()
    return fn(*args)


def make_executor(kind: str, workers: int | None = None, address: str | None = None) -> Executor:
    """``local`` (``workers`` processes, default all cores) or ``ray`` (``address``: None, auto, ray://...)."""
    if kind == "local":
        if address:
            raise InputError("--address needs --executor ray")
        return LocalExecutor(workers or default_workers())
    if kind == "ray":
        return RayExecutor(address, workers)
    raise InputError(f"--executor must be one of {', '.join(EXECUTORS)}, got {kind!r}")


def map_unordered(
    executor: Executor,
    calls: Sequence[tuple[Any, ...]] | Iterable[tuple[Any, ...]],
    window: int | None = None,
) -> Iterator[tuple[int, Any]]:
    """Run each ``(fn, *args)`` of ``calls``; yield ``(index, result)`` as they finish, with at most
    ``window`` (default twice the slots) in flight so an interrupt loses little work."""
    todo = list(calls)
    limit = window or 2 * executor.slots
    pending: dict[Any, int] = {}
    queue = list(reversed(range(len(todo))))
    try:
        while queue or pending:
            while queue and len(pending) < limit:
                k = queue.pop()
                fn, *args = todo[k]
                pending[executor.submit(fn, *args)] = k
            finished, _ = executor.wait_any(set(pending))
            for handle in [h for h in pending if h in finished]:  # in submission order
                k = pending.pop(handle)
                yield k, executor.result(handle)
    finally:
        if pending and isinstance(executor, RayExecutor):
            for handle in pending:
                executor._ray.cancel(handle, force=True)

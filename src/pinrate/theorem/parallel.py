"""Running chunks of work on one process, on worker processes, or on a Dask cluster.

Work-volume tests are embarrassingly parallel: configurations are drawn once in the caller
(so the result does not depend on how the work is split), cut into chunks, and each chunk
is evaluated where it is sent. A robot travels as its
:class:`~pinrate.kinematics.RobotSpec` (URDF text and frames) and is rebuilt once per
worker process (:func:`pinrate.kinematics.urdf.robot_from_spec`).
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any, TypeVar

from tqdm.auto import tqdm

from ..checks import check_count
from ..errors import InputError, SchedulerError

T = TypeVar("T")
"""What the function mapped over the chunks returns for one chunk."""

SCHEDULER_TIMEOUT = 5.0
"""Seconds to wait for a Dask scheduler before a SchedulerError."""


def _progress(total: int, description: str, enabled: bool | None) -> Any:
    # enabled=None: tqdm shows the bar only on a terminal.
    return tqdm(
        total=total, desc=description, unit="chunk", disable=None if enabled is None else not enabled, leave=False
    )


def check_workers(workers: object) -> int:
    """Workers to use (processes, or the compiled core's threads): a positive integer, at
    most the CPU count."""
    count = check_count(workers, "workers", minimum=1)
    return min(count, os.cpu_count() or 1) if count > 1 else 1


def map_chunks(
    function: Callable[..., T],
    chunks: Sequence[Any],
    *arguments: Any,
    workers: int = 1,
    scheduler: object = None,
    progress: bool | None = None,
    description: str = "",
) -> list[T]:
    """``[function(*arguments, chunk) for chunk in chunks]``, in order, wherever asked.

    Args:
        function: a module-level (picklable) function.
        workers: processes on this machine (1: in this process).
        scheduler: a Dask scheduler address (``"tcp://host:8786"``), a
            ``distributed.Client``, or a cluster object with a ``scheduler_address``; takes
            precedence over ``workers``. Needs the optional ``dask`` extra.
        progress: show a progress bar (None: only on a terminal).
    """
    workers = check_workers(workers)
    results: list[Any] = [None] * len(chunks)
    with _progress(len(chunks), description, progress) as bar:
        if scheduler is not None:
            client, owned = _dask_client(scheduler)
            try:
                futures = {client.submit(function, *arguments, chunk, pure=False): i for i, chunk in enumerate(chunks)}
                from distributed import as_completed as dask_completed

                for future in dask_completed(futures):
                    results[futures[future]] = future.result()
                    bar.update(1)
            finally:
                if owned:
                    client.close()
        elif workers > 1 and len(chunks) > 1:
            # Ctrl-C reaches the whole process group: the workers leave it to this process,
            # which cancels what is queued, instead of each printing a traceback.
            pool = ProcessPoolExecutor(max_workers=workers, initializer=_ignore_interrupts)
            try:
                futures = {pool.submit(function, *arguments, chunk): i for i, chunk in enumerate(chunks)}
                for future in as_completed(futures):
                    results[futures[future]] = future.result()
                    bar.update(1)
            finally:
                pool.shutdown(wait=True, cancel_futures=True)
        else:
            for i, chunk in enumerate(chunks):
                results[i] = function(*arguments, chunk)
                bar.update(1)
    return results


def _ignore_interrupts() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _dask_client(scheduler: object) -> tuple[Any, bool]:
    try:
        from distributed import Client
    except ImportError:
        raise InputError("a Dask scheduler needs the optional extra: pip install 'pinrate[dask]'") from None
    if isinstance(scheduler, Client):
        return scheduler, False
    address = getattr(scheduler, "scheduler_address", scheduler)
    if not isinstance(address, str):
        raise InputError(f"scheduler must be an address, a distributed.Client or a cluster, not {scheduler!r}")
    return _connect(Client, address), True


def _connect(client_class: Any, address: str) -> Any:
    """A Client of the scheduler at ``address``, or a PinrateError within about
    SCHEDULER_TIMEOUT seconds. distributed's own timeout covers the TCP connection, not a
    peer that accepts and never speaks (or speaks HTTP: its reply parses as a 3 EiB frame),
    so the attempt runs in a daemon thread that is abandoned if it does not return."""
    outcome: dict[str, Any] = {}

    def attempt() -> None:
        try:
            outcome["client"] = client_class(address, timeout=SCHEDULER_TIMEOUT)
        except BaseException as error:  # handed to the caller's thread below
            outcome["error"] = error

    thread = threading.Thread(target=attempt, name="pinrate-dask-connect", daemon=True)
    thread.start()
    thread.join(2 * SCHEDULER_TIMEOUT)
    error = outcome.get("error")
    if thread.is_alive():
        raise SchedulerError(f"{address!r} did not answer as a Dask scheduler within {2 * SCHEDULER_TIMEOUT:g} s")
    if isinstance(error, ValueError):
        raise InputError(f"scheduler address {address!r} is not valid: {error}")
    if isinstance(error, TypeError):  # tls:// without security settings, and the like
        raise InputError(
            f"scheduler {address!r}: {error}; for a secured cluster pass a distributed.Client instead of an address"
        )
    if isinstance(error, OSError | MemoryError):
        reason = str(error) if isinstance(error, OSError) else "its reply is not Dask's protocol"
        raise SchedulerError(f"no Dask scheduler reachable at {address!r} within {SCHEDULER_TIMEOUT:g} s: {reason}")
    if error is not None:
        raise error
    return outcome["client"]

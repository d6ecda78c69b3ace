"""Run a sweep: the chunks not stored yet, on Dask workers or in this process, each written as it comes back.

Workers only compute (a chunk's columns go back to this process), and this
process alone writes the store: a remote cluster needs no shared file system,
and there is one writer. A Dask LocalCluster of worker *processes* runs by
default, one per core (threads would share heyroll's cached integrators, see
points.py); ``workers=1``, or a sweep with one chunk left to run, runs here
without Dask.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import sys
import threading
from collections import Counter
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path

import numpy as np

from ..interfaces.outputs import busy_message, hold_directory, writable_problem
from ..simulation.driver import signal_handled, signals_deferred
from .errors import SchedulerError, SweepError
from .plan import SweepPlan, make_plan
from .points import Chunk, run_chunk
from .store import SPEC_ATTR, ChunkWriter, check_spec, open_or_create, open_sweep, store_path, stored_mask

#: Seconds to wait for a --scheduler to answer before giving up (one line, exit 2).
SCHEDULER_TIMEOUT = 10
#: Seconds a scheduler is given to have a worker before the sweep is refused.
WORKER_WAIT = 30


@dataclass(frozen=True)
class SweepOutcome:
    """What a sweep did: its store, point counts, and the status counts of every stored point."""

    path: Path
    points: int
    stored_before: int  # points already in the store when this run started (a resumed sweep)
    statuses: dict  # status -> number of points

    def summary_line(self) -> str:
        counts = ", ".join(f"{n} {status}" for status, n in sorted(self.statuses.items(), key=lambda x: (-x[1], x[0])))
        return f"{self.points} point{'' if self.points == 1 else 's'}: {counts}"


def run_sweep(scene=None, *, scene_text=None, vary=None, values=None, random=None, samples=None, seed=None,
              keep=None, out="heyroll-sweep", workers=None, scheduler=None, client=None, t_end=None,
              max_collisions=..., progress=False, figures=False, chunk_points=None, precision=None, batch=None):
    """Run a sweep and return its store as an xarray Dataset (README, "Sweeps").

    ``scene``: a scene file path (None: the default scene) or ``scene_text``.
    ``vary={"collision.restitution": (0.5, 1.0, 11)}`` (or "0.5:1.0:11") is a
    grid axis from START to STOP in N values; ``values={"bodies[2].mass": [1,
    2, 4]}`` an axis of listed values (dimensions in that order: vary, then
    values); ``random={"frame.omega": (0, 3)}`` with ``samples`` and ``seed``
    draws random points instead. Without any, the scene file's [sweep] table
    says. ``keep``: a comma list (or a list) of "summary", "impacts:M",
    "first:M", "strobe:M", "period", "lyapunov", "rotation". ``precision``:
    "double" (default), "long", "quad" or "mp:BITS", every point's. ``batch``: points
    of one shape through heyoka's batch (SIMD) integrator (README, "Sweeps": faster, not the
    scalar run's last bits). The store is ``out``/sweep.zarr;
    a sweep that finds its own store there (same spec) runs only the points
    not stored yet, and refuses another sweep's store (SweepStoreError).
    ``workers``: processes of a LocalCluster (default: all cores; 1 runs
    here, without Dask); ``scheduler``: a running dask.distributed
    scheduler's address; ``client``: a dask.distributed Client to use.
    Ctrl-C raises KeyboardInterrupt once the cluster is closed; the chunks
    finished so far are stored.
    """
    grid = [("vary", _entry(k, v, ":")) for k, v in _items(vary)] + \
           [("values", _entry(k, v, ",")) for k, v in _items(values)]
    plan = make_plan(scene, scene_text=scene_text, grid=grid, random=[_entry(k, v, ":") for k, v in _items(random)],
                     samples=samples, seed=seed, keep=keep, t_end=t_end, max_collisions=max_collisions,
                     chunk_points=chunk_points, precision=precision, batch=batch)
    given = dict(scene=None if scene is None else str(scene), vary=vary, values=values, random=random,
                 samples=samples, seed=seed, keep=keep, t_end=t_end,
                 max_collisions=None if max_collisions is ... else max_collisions, precision=precision,
                 batch=batch)
    command = "heyroll.sweep.run_sweep(" + ", ".join(f"{k}={v!r}" for k, v in given.items() if v is not None) + ")"
    outcome = execute(plan, Path(out), workers=workers, scheduler=scheduler, client=client, progress=progress,
                      command=command)
    if figures:
        from .figures import sweep_figures

        sweep_figures(outcome.path, Path(out))
    return open_sweep(outcome.path)


def _items(spec) -> list:
    """(KEY, spec) pairs from a dict, or from "KEY=SPEC" strings."""
    if spec is None:
        return []
    if isinstance(spec, dict):
        return list(spec.items())
    if isinstance(spec, str):
        spec = [spec]
    return [tuple(entry.split("=", 1)) if isinstance(entry, str) and "=" in entry else (entry, None) for entry in spec]


def _entry(key, spec, sep: str) -> str:
    """ "KEY=SPEC" from an API value: text as it is, numbers by their shortest decimal text."""
    if spec is None:
        raise SweepError(str(key), 'expected "KEY=SPEC" or {KEY: SPEC}')
    if isinstance(spec, str):
        return f"{key}={spec}"
    if isinstance(spec, (int, float, Decimal)):
        spec = [spec]
    return f"{key}={sep.join(_number_text(v) for v in spec)}"


def _number_text(value) -> str:
    if isinstance(value, bool) or not isinstance(value, (int, float, Decimal, str)):
        raise SweepError("sweep", f"expected a number, got {value!r}")
    return repr(value) if isinstance(value, float) else str(value)


def execute(plan: SweepPlan, out: Path, *, workers=None, scheduler=None, client=None, progress=False,
            command: str = "", report=None, after_chunk=None) -> SweepOutcome:
    """Run the points of ``plan`` not stored yet in ``out``/sweep.zarr; the store after the last chunk.

    Checks the store (refused: SweepStoreError) and the scheduler (unreachable:
    SchedulerError) before anything is written. ``report(text)`` receives the
    dashboard's address; ``after_chunk(n)`` is called after the n-th chunk
    written (tests stop a sweep there, as a kill between chunks would).
    """
    from ..interfaces.outputs import versions

    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise SweepError("--workers", f"must be a whole number >= 1, got {workers!r}")
    path = store_path(out)
    stored = np.zeros(plan.n_points, dtype=bool)
    if path.exists():
        check_spec(path, plan, versions())
        stored = stored_mask(path)
    before = int(stored.sum())
    pending = [(region, first, count) for region, first, count in plan.regions()
               if not stored[first:first + count].all()]
    attrs = {
        SPEC_ATTR: json.dumps(plan.spec(), sort_keys=True),
        "versions": versions(),
        "scene": plan.text,
        "scene_source": plan.source,
        "command": command,
        "coordinate": plan.coordinate,
        "precision": plan.precision,
        "batch": plan.batch,
    }
    with _executor(len(pending), workers, scheduler, client) as (submit, dashboard), contextlib.ExitStack() as stack:
        if dashboard and report is not None:
            report(f"dask dashboard: {dashboard}")
        held = _writable(out)  # after the scheduler answered: an unreachable one leaves nothing behind
        stack.callback(held.close)
        path = open_or_create(plan, out, attrs)
        writer = ChunkWriter(path)
        with _progress_bar(progress, plan.n_points, before) as bar:
            for n, (region, count, columns) in enumerate(submit(plan, pending), start=1):
                with signals_deferred():  # a chunk is written whole before Ctrl-C or SIGTERM acts
                    writer.write(region, columns)
                bar.update(count)
                if after_chunk is not None:
                    after_chunk(n)
    import zarr

    statuses = zarr.open_array(str(path / "status"), mode="r")[...].reshape(-1)
    return SweepOutcome(path, plan.n_points, before, dict(Counter(str(s) for s in statuses)))


def _chunk(plan: SweepPlan, first: int, count: int) -> Chunk:
    return Chunk(plan.data, plan.default_name, plan.keys, tuple(plan.point_values(p) for p in range(first, first + count)),
                 plan.t_end, plan.max_collisions, plan.keep, plan.n_bodies, plan.precision, plan.batch)


def _in_process(plan: SweepPlan, pending: list):
    for region, first, count in pending:
        yield region, count, run_chunk(_chunk(plan, first, count))


@contextlib.contextmanager
def _executor(chunks: int, workers, scheduler, client):
    """(submit, dashboard address or None): ``submit(plan, pending)`` yields (region, count, columns) as chunks finish.

    ``chunks`` left to run: with at most one (or ``workers=1``) and no scheduler or client, no cluster is started.
    """
    if client is None and scheduler is None and (workers == 1 or chunks <= 1):
        yield _in_process, None
        return
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise SweepError("--workers", "running on Dask needs dask.distributed: pip install 'heyroll[sweep]' "
                         "(or --workers 1 to run in this process)") from None
    with contextlib.ExitStack() as stack:
        if client is None:
            if scheduler is not None:
                client = stack.enter_context(_connect(Client, scheduler))
            else:
                import logging

                # The workers start with Ctrl-C ignored (a terminal's Ctrl-C reaches the whole process group):
                # this process stops the sweep and closes the cluster; each worker printed its own traceback
                # of the interruption (review). The price: a Ctrl-C while the cluster starts (its first 1-2 s)
                # is not seen (README). Blocking it instead, to act on it after, was measured: the workers
                # Dask spawns do not all keep the mask (a traceback again), and here a signal that is blocked
                # and ignored is dropped.
                with signal_handled(signal.SIGINT, signal.SIG_IGN):
                    cluster = stack.enter_context(LocalCluster(
                        n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                        # (CRITICAL: a worker's "failed to communicate with scheduler during heartbeat" as the
                        # cluster closes printed a 30-line traceback after a completed sweep, acceptance test; a
                        # task's own error reaches this process through its future)
                        dashboard_address=":0", silence_logs=logging.CRITICAL))
                client = stack.enter_context(Client(cluster))

        def submit(plan: SweepPlan, pending: list):
            # Closing the client (Ctrl-C, an error) releases the futures: the scheduler drops their tasks.
            futures = {client.submit(run_chunk, _chunk(plan, first, count), pure=False): (region, count)
                       for region, first, count in pending}
            for future in as_completed(futures):
                region, count = futures[future]
                yield region, count, future.result()

        yield submit, client.dashboard_link


@contextlib.contextmanager
def _connect(client_class, address: str):
    """A client of the scheduler at ``address``, or SchedulerError within twice SCHEDULER_TIMEOUT.

    Dask's own timeout covers the TCP connection, not its handshake: a service that accepts and stays
    silent (an HTTP server) held the sweep for minutes, and one that answers with text (a banner) made
    Dask read it as a frame length and fail with a MemoryError (review). So the client is made in a
    daemon thread this one waits for, and any error of it is the scheduler's."""
    made: dict = {}

    def make():
        try:
            made["client"] = client_class(address, timeout=SCHEDULER_TIMEOUT)
        except Exception as exc:  # noqa: BLE001 (whatever answered, it is not a scheduler we can use)
            made["error"] = exc

    thread = threading.Thread(target=make, name="heyroll-scheduler-connect", daemon=True)
    thread.start()
    thread.join(2 * SCHEDULER_TIMEOUT)
    if thread.is_alive():
        raise SchedulerError("--scheduler", f"cannot reach the dask scheduler at {address}: no answer within "
                                            f"{2 * SCHEDULER_TIMEOUT} s (is a dask scheduler listening there?)")
    if "error" in made:
        exc = made["error"]
        if isinstance(exc, (OSError, TimeoutError, ValueError)):
            detail = str(exc).splitlines()[0] if str(exc) else exc.__class__.__name__
        else:
            detail = f"what answers there is not a dask scheduler ({exc.__class__.__name__})"
        raise SchedulerError("--scheduler", f"cannot reach the dask scheduler at {address}: {detail}")
    with made["client"] as client:
        # a scheduler with no worker takes the tasks and runs none: the sweep waited in silence (review)
        try:
            client.wait_for_workers(1, timeout=WORKER_WAIT)
        except TimeoutError:
            raise SchedulerError("--scheduler", f"the dask scheduler at {address} has no worker (none joined within "
                                                f"{WORKER_WAIT} s): start one with 'dask worker {address}'") from None
        yield client


@contextlib.contextmanager
def _progress_bar(mode, total: int, initial: int):
    """A tqdm bar over points (mode: True/'on', False/'off', or 'auto': on a terminal)."""
    import tqdm

    disable = {"on": False, True: False, "off": True, False: True, "auto": None}[mode]
    # miniters=1: every stored chunk is shown (tqdm's own pacing skipped chunks: the bar said 188 of 3000 at a
    # Ctrl-C that left 376 stored, acceptance test; a chunk is hundreds of points, its update costs nothing)
    with tqdm.tqdm(total=total, initial=initial, unit="point", desc="sweep", disable=disable, file=sys.stderr,
                   miniters=1, mininterval=0) as bar:
        yield bar


def _writable(out: Path):
    """Create ``out``, check it can be written and hold it (outputs.hold_directory): the open lock file."""
    problem = writable_problem(out)
    if problem:
        raise SweepError("--out", problem)
    handle = hold_directory(out)
    if handle is None:
        raise SweepError("--out", busy_message(out))
    return handle
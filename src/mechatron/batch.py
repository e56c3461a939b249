"""Batch runs: one compiled model, many parameter sets, on local processes or Dask.

Monte Carlo and Sobol studies (:mod:`mechatron.estimation.sensitivity`) and parameter
sweeps (:func:`sweep`) evaluate one model at many points. :func:`map_blocks` runs a
function over blocks of those points:

* in this process (``workers=1``), or on local worker processes
  (:class:`concurrent.futures.ProcessPoolExecutor`, the model sent once per process by
  its initializer);
* on a ``dask.distributed`` cluster (``client=`` a :class:`distributed.Client`, or
  ``address=`` a scheduler's address; install the ``dask`` extra). The shared object
  (the compiled model, a problem) is scattered to every worker once
  (``broadcast=True``), so each worker unpickles it once, not once per block; each block
  is a task that is retried (``retries``) if it fails, and a block whose worker dies is
  rerun by the scheduler on another worker. If the shared object itself is lost (the
  scheduler's memory manager may keep one replica of scattered data, and a worker that
  dies with the last one takes it along), it is scattered again and the blocks not yet
  collected rerun, up to ``retries`` times. Results come back in the order of the blocks,
  so a run on a cluster gives the same numbers as a local one.

:func:`received` counts, in the calling process, how many times a shared object was
unpickled there (``client.run(mechatron.batch.received)`` asks every worker).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from concurrent.futures import CancelledError, ProcessPoolExecutor
from typing import Any

import numpy as np

__all__ = ["map_blocks", "sweep", "received", "Shared"]

_RECEIVED = {"count": 0}
_LOCAL: dict = {}


class Shared:
    """An object sent once to each worker (a compiled model, a problem); counts its
    arrivals in the receiving process (see :func:`received`)."""

    __slots__ = ("value",)

    def __init__(self, value: Any):
        self.value = value

    def __getstate__(self):
        return {"value": self.value}

    def __setstate__(self, state):
        self.value = state["value"]
        _RECEIVED["count"] += 1


def received() -> int:
    """How many shared objects this process has unpickled (run on workers by Dask's
    ``client.run`` to check that a model was shipped once per worker)."""
    return _RECEIVED["count"]


def _client(client, address: str | None):
    """``(client, owned)``: the Dask client to use, and whether it was opened here."""
    if client is not None:
        return client, False
    try:
        from dask.distributed import Client    # optional dependency
    except ImportError as exc:
        from mechatron.errors import ParameterError
        raise ParameterError(f"batch: running on the Dask cluster at {address} needs "
                             f"dask.distributed, which cannot be imported ({exc}). Install "
                             "it (pip install \"dask[distributed]\", or the project's "
                             "'dev' extra), or give no address to use local "
                             "processes.") from None
    return Client(address), True


def _call(fn, shared: Shared, block):
    return fn(shared.value, block)


def _init_local(shared: Shared) -> None:
    _LOCAL["shared"] = shared


def _call_local(args):
    fn, block = args
    return fn(_LOCAL["shared"].value, block)


def map_blocks(fn: Callable[[Any, Any], Any], shared: Any, blocks: Sequence, *,
               workers: int | None = 1, client=None, address: str | None = None,
               retries: int = 2, progress: Callable[[int, int], None] | None = None) -> list:
    """``[fn(shared, block) for block in blocks]``, in parallel.

    Parameters
    ----------
    fn : callable
        A module-level function (workers import it by name) of the shared object and one
        block.
    shared : object
        Sent once to each worker process (picklable; a compiled model pickles its CasADi
        functions).
    blocks : sequence
        The work, one task per block.
    workers : int, optional
        Local worker processes when no cluster is given: 1 runs in this process, None
        uses every core.
    client : distributed.Client, optional
        Run on this Dask cluster.
    address : str, optional
        Or connect to the Dask scheduler at this address (closed again at the end).
    retries : int
        Times a failed task is rerun on the cluster, and times the shared object is
        scattered again after the cluster lost it.
    progress : callable, optional
        Called with (blocks done, blocks) as results arrive, in block order.

    Returns
    -------
    list
        One result per block, in the order of `blocks`.
    """
    n = len(blocks)
    out: list = [None] * n
    if client is not None or address:
        cl, owned = _client(client, address)
        try:
            k, lost = 0, 0
            while k < n:
                remote = cl.scatter(Shared(shared), broadcast=True, hash=False)
                futures = [cl.submit(_call, fn, remote, block, pure=False, retries=retries)
                           for block in blocks[k:]]
                try:
                    for fut in futures:
                        out[k] = fut.result()
                        k += 1
                        if progress:
                            progress(k, n)
                except CancelledError:
                    # the shared object's last copy died with a worker (the scheduler
                    # may keep a single replica of scattered data, and cannot recompute
                    # it): scatter it again and rerun the blocks not yet collected
                    cl.cancel(futures)
                    lost += 1
                    if lost > retries:
                        raise RuntimeError(
                            f"batch: the cluster lost the shared object with the worker "
                            f"that held it {lost} times ({k} of {n} blocks done); check "
                            "the workers' logs for why they die (memory limits?), or "
                            "allow more retries.") from None
        finally:
            if owned:
                cl.close()
        return out
    workers = workers if workers is not None else (os.cpu_count() or 1)
    if workers <= 1 or n <= 1:
        for k, block in enumerate(blocks):
            out[k] = fn(shared, block)
            if progress:
                progress(k + 1, n)
        return out
    with ProcessPoolExecutor(max_workers=workers, initializer=_init_local,
                             initargs=(Shared(shared),)) as pool:
        for k, res in enumerate(pool.map(_call_local, [(fn, b) for b in blocks])):
            out[k] = res
            if progress:
                progress(k + 1, n)
    return out


def _simulate_block(job: dict, block: list[dict]) -> list:
    """Simulations of one block of a sweep: a list of SimResult, each with the outputs
    asked for (every variable if none)."""
    import mechatron as mt
    out = []
    for params in block:
        res = mt.simulate(job["model"], job["t_stop"], params=params, **job["options"])
        out.append(res.select(*job["outputs"]) if job["outputs"] else
                   res.select(*res.names))
    return out


def sweep(model, params: Sequence[dict], t_stop: float, *,
          outputs: Sequence[str] | None = None, block_size: int | None = None,
          workers: int | None = 1, client=None, address: str | None = None,
          progress: Callable[[int, int], None] | None = None, **options) -> list:
    """Simulate one model for each parameter set, locally or on a Dask cluster.

    Parameters
    ----------
    model : Component or CompiledModel
        Compiled here once if a component; the compiled model is what the workers get
        (once each).
    params : sequence of dict
        One ``params=`` dict of :func:`mechatron.simulate` per run.
    t_stop : float
        End time of every run, in s.
    outputs : sequence of str, optional
        Variables (or components) each result keeps; all if omitted (more to send back).
    block_size : int, optional
        Runs per task (default: about four tasks per worker).
    workers, client, address, progress
        Where to run: see :func:`map_blocks`.
    **options
        Further keywords of :func:`mechatron.simulate` (solver, rtol, t_out, ...).

    Returns
    -------
    list of SimResult
        In the order of `params`; the same values wherever they ran.
    """
    import mechatron as mt
    cm = model if isinstance(model, mt.CompiledModel) else mt.compile_model(model)
    params = list(params)
    if not params:
        return []
    slots = 4 * max(1, workers or (os.cpu_count() or 1)) if client is None and not address \
        else 16
    size = block_size or max(1, int(np.ceil(len(params) / slots)))
    blocks = [params[k:k + size] for k in range(0, len(params), size)]
    job = {"model": cm, "t_stop": float(t_stop), "outputs": list(outputs or []),
           "options": options}
    results = map_blocks(_simulate_block, job, blocks, workers=workers, client=client,
                         address=address, progress=progress)
    return [res for block in results for res in block]

"""Batch runs on a Dask LocalCluster of two worker processes: the same results as a local
run, a killed worker's task rerun, the compiled model shipped once per worker."""

import os
from pathlib import Path

import numpy as np
import pytest

import mechatron as mt
from mechatron import batch
from mechatron.library import electrical as el

distributed = pytest.importorskip("distributed")


class RC(mt.Component):
    """A source charging a capacitor through a resistor: ``v = V (1 - exp(-t/RC))``."""

    src = el.DCVoltageSource(V=2.0)
    r = el.Resistor(R=10.0)
    c = el.Capacitor(C=1e-3)
    gnd = el.ElectricalReference()

    def equations(self):
        return [mt.connect(self.src.p, self.r.p), mt.connect(self.r.n, self.c.p),
                mt.connect(self.c.n, self.src.n, self.gnd.port)]


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=40) as cluster, \
            distributed.Client(cluster) as cl:
        yield cl


@pytest.fixture(scope="module")
def cm():
    return mt.compile_model(RC())


def test_a_sweep_on_the_cluster_equals_the_local_run_and_the_physics(client, cm):
    params = [{"r.R": R, "c.C": C} for R in (5.0, 10.0, 20.0) for C in (1e-3, 2e-3)]
    opts = dict(outputs=["c.v", "r.i"], t_out=np.linspace(0.0, 0.05, 51), rtol=1e-9,
                atol=1e-12)
    local = batch.sweep(cm, params, 0.05, workers=1, **opts)
    before = client.run(batch.received)     # (the module's tests share the cluster)
    remote = batch.sweep(cm, params, 0.05, client=client, block_size=2, **opts)
    assert len(remote) == len(params)
    for a, b, p in zip(local, remote, params):
        np.testing.assert_array_equal(a.values, b.values)     # identical, in order
        tau = p["r.R"] * p["c.C"]
        np.testing.assert_allclose(b["c.v"], 2.0 * (1.0 - np.exp(-b.t / tau)), atol=1e-6)
    # the model arrived once at each worker (scattered to all), though three blocks of
    # two ran
    after = client.run(batch.received)
    assert [count - before.get(worker, 0) for worker, count in after.items()] == [1, 1]


def _once_then_die(shared, block):
    """Kill this worker process on the first attempt at a block (marker file), else
    simulate: the scheduler must rerun the block on a worker that lives."""
    marker = Path(shared["marker"])
    if block == shared["victim"] and not marker.exists():
        marker.write_text(str(os.getpid()))
        os._exit(1)
    res = mt.simulate(shared["model"], 0.02, params={"r.R": block}, rtol=1e-9, atol=1e-12)
    return float(res.final("c.v"))


def test_a_killed_worker_s_task_is_rerun(client, cm, tmp_path):
    job = {"model": cm, "marker": str(tmp_path / "killed"), "victim": 7.0}
    blocks = [3.0, 5.0, 7.0, 11.0]
    got = batch.map_blocks(_once_then_die, job, blocks, client=client)
    assert (tmp_path / "killed").exists()               # a worker did die
    want = [2.0 * (1.0 - np.exp(-0.02 / (R * 1e-3))) for R in blocks]
    np.testing.assert_allclose(got, want, atol=1e-7)
    local = batch.map_blocks(_once_then_die, job, blocks, workers=1)
    assert got == local
    client.wait_for_workers(2, timeout=60)     # the nanny's new worker: the module's
                                               # cluster whole again for the next test


def test_a_lost_shared_object_is_scattered_again(cm, tmp_path):
    """A cluster of one worker: the worker that dies takes the only copy of the shared
    model with it (the scheduler cannot recompute scattered data). The nanny starts a new
    worker; the model is scattered to it again and the blocks not yet done rerun."""
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=":0", silence_logs=50) as cluster, \
            distributed.Client(cluster) as cl:
        job = {"model": cm, "marker": str(tmp_path / "killed"), "victim": 5.0}
        blocks = [3.0, 5.0, 7.0]
        seen = []
        got = batch.map_blocks(_once_then_die, job, blocks, client=cl,
                               progress=lambda k, n: seen.append((k, n)))
        assert (tmp_path / "killed").exists()           # the worker did die
    want = [2.0 * (1.0 - np.exp(-0.02 / (R * 1e-3))) for R in blocks]
    np.testing.assert_allclose(got, want, atol=1e-7)
    assert seen == [(1, 3), (2, 3), (3, 3)]             # each block reported once, in order


def _shipped(job, block):
    return os.getpid(), batch.received()


def test_the_shared_object_is_shipped_once_per_worker(client, cm):
    before = client.run(batch.received)
    pids = batch.map_blocks(_shipped, {"model": cm}, list(range(12)), client=client)
    after = client.run(batch.received)
    # each worker (the two of the cluster, or one that replaced a killed one) got the
    # model of this call at most once, whatever number of blocks it ran, and the ones
    # that ran blocks got it
    delta = {a: c - before.get(a, 0) for a, c in after.items()}
    assert all(d <= 1 for d in delta.values())
    assert sum(delta.values()) >= 1 and len(pids) == 12


def test_sensitivity_on_the_cluster_equals_the_local_run(client):
    from mechatron.estimation import sensitivity as sens

    class Problem:
        """A stand-in with the problem's interface: one requirement, cost = sse."""
        names = ["k"]
        initial = np.array([1.0])
        bound = [{"out_labels": ["y"], "Ym": [np.zeros(3)], "sigma": [1.0]}]

        def simulate(self, theta):
            return [{"y": theta[0] * np.array([1.0, 2.0, 3.0])}]

    X = np.linspace(0.5, 1.5, 20).reshape(-1, 1)
    local = sens.evaluate(Problem(), ["k"], X, workers=1)
    remote = sens.evaluate(Problem(), ["k"], X, client=client)
    np.testing.assert_array_equal(local, remote)
    np.testing.assert_allclose(local[:, 0], 14.0 * X[:, 0] ** 2)

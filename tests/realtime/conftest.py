"""Shared by the real-time tests: a free-running run whose schedule was kept."""

import pytest

from mechatron.realtime.hil import STALL_S, run_hil


def _on_schedule(name, tries=3, **kwargs):
    """``run_hil(name, mode="sil", **kwargs)``, free-running, whose schedule was kept. A
    virtual machine's host can pause the whole machine for tenths of a second; the plant
    then runs on with the duty held, and the run reports the stall
    (`HILResult.longest_gap`, a note). Such a run measures the pause, not the controller:
    it is run again, up to ``tries`` runs; if every one stalled, the test fails saying so."""
    rate = kwargs.get("rate", 10_000.0)
    for _ in range(tries):
        res = run_hil(name, mode="sil", **kwargs)
        if res.longest_gap < STALL_S * rate:
            return res
        assert any("stalled" in n for n in res.notes)
    pytest.fail(f"the machine stalled the real-time loop in each of {tries} runs (the "
                f"last: {res.longest_gap} steps without an exchange); no run to compare")


@pytest.fixture
def on_schedule():
    """`_on_schedule`: a SIL run that kept its schedule, run again after a host's pause."""
    return _on_schedule

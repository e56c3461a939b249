"""PIL: the controller cross-compiled for a Cortex-M3 and run on QEMU's lm3s6965evb."""

import shutil

import numpy as np
import pytest

from mechatron.realtime.hil import qemu_available, run_hil

why = qemu_available()
pytestmark = pytest.mark.skipif(
    why is not None or shutil.which("cc") is None,
    reason=f"PIL needs QEMU and the ARM toolchain: {why} (.ci/run installs them as root)")


def test_pil_firmware_boots_and_closes_the_loop():
    res = run_hil("speed", mode="pil", duration=0.08, rate=10_000.0)
    s = res.summary()
    assert s["steps"] == 800
    # the firmware answered every sample and reported over semihosting before exiting
    assert res.controller.get("samples") == 800 and res.controller.get("stopped") is True
    assert s["missed_steps"] == 0
    # a closed loop: the speed left 0 towards the reference step at 0.05 s
    assert res.log["w"][-1] > 10.0
    assert s["rms_diff_percent"] < 2.0
    # the generated controller on the Cortex-M3 (soft-float doubles) gives MIL's duty
    np.testing.assert_allclose(res.log["duty"], res.mil["duty"], rtol=0, atol=1e-12)
    assert any("real time" in n for n in s["notes"])     # says how fast it really ran

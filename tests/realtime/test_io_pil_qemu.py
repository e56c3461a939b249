"""PIL over the serial protocol: the Python serial backend against the controller
firmware cross-compiled for the Cortex-M3 and run by QEMU (lm3s6965evb), its UART0 on a
pseudo-terminal."""

import os
import shutil
import subprocess

import numpy as np
import pytest

from mechatron.realtime.cgen import build_firmware, build_reference_firmware
from mechatron.realtime.hil import QEMU_MACHINE, qemu_available
from mechatron.realtime.io import SerialIO
from mechatron.realtime.loop import build_loop, run_mil
from mechatron.realtime.plant_loop import run_plant

why = qemu_available()
pytestmark = pytest.mark.skipif(
    why is not None or shutil.which("cc") is None,
    reason=f"PIL needs QEMU and the ARM toolchain: {why} (tools/sysdeps.sh installs "
           "them as root)")


def test_serial_backend_drives_the_firmware_in_qemu(tmp_path):
    loop = build_loop("position", rate=10_000.0)
    elf = build_firmware(loop, tmp_path)
    master, slave = os.openpty()
    qemu = subprocess.Popen([shutil.which("qemu-system-arm"), "-M", QEMU_MACHINE,
                             "-nographic", "-monitor", "none", "-serial", "chardev:u0",
                             "-chardev", f"serial,id=u0,path={os.ttyname(slave)}",
                             "-semihosting-config", "enable=on,target=native",
                             "-kernel", str(elf)],
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    io = SerialIO(fd=master)
    try:
        steps = 600
        out = run_plant(io, loop, rate=10_000.0, duration=steps / 1e4, lockstep=2.0,
                        hello_timeout=30.0)
        console = qemu.communicate(timeout=30)[0]
    finally:
        if qemu.poll() is None:
            qemu.kill()
        io.close()
        os.close(slave)
    s = out["stats"]
    assert s["received"] == steps and s["lost"] == 0 and s["bad_frames"] == 0
    assert '"samples": 600' in console            # the firmware's own count, semihosting
    mil = run_mil(loop, steps)
    np.testing.assert_allclose(out["log"]["duty"], mil["duty"], rtol=0, atol=1e-12)
    assert mil["phi"][-1] > 0.1                   # the position loop moved the shaft


def test_reference_firmware_fixed_rate_loop_in_qemu(tmp_path):
    """The reference firmware (mt_fw.c on the SysTick board layer, ticking at 1 kHz of
    the emulated clock) over the serial protocol: every sample answered, duty as MIL;
    and its wired variant (controller on the board's encoder, PWM out) builds too."""
    loop = build_loop("speed", rate=10_000.0)
    local = build_reference_firmware(loop, tmp_path / "local", rate=1000, local=True)
    assert local.stat().st_size > 0
    elf = build_reference_firmware(loop, tmp_path / "serial", rate=1000)
    master, slave = os.openpty()
    qemu = subprocess.Popen([shutil.which("qemu-system-arm"), "-M", QEMU_MACHINE,
                             "-nographic", "-monitor", "none", "-serial", "chardev:u0",
                             "-chardev", f"serial,id=u0,path={os.ttyname(slave)}",
                             "-kernel", str(elf)],
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    io = SerialIO(fd=master)
    try:
        steps = 200
        out = run_plant(io, loop, rate=10_000.0, duration=steps / 1e4, lockstep=2.0,
                        hello_timeout=30.0)
    finally:
        qemu.kill()
        qemu.wait()
        io.close()
        os.close(slave)
    s = out["stats"]
    assert s["received"] == steps and s["lost"] == 0 and s["bad_frames"] == 0
    np.testing.assert_allclose(out["log"]["duty"], run_mil(loop, steps)["duty"], rtol=0,
                               atol=1e-12)

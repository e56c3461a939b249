"""Sources with a start time and an offset (MSL's Electrical.Analog.Sources): each
voltage source drives an RC low-pass, checked against a hand-written SciPy model of the
same circuit fed by the waveform written here in NumPy (integrated piece by piece between
the waveform's breakpoints); each current source charges a capacitor, checked against the
exact integral of the waveform. The events counted are the waveform's breakpoints."""

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

import mechatron as mt
from mechatron.errors import DataError
from mechatron.library import blocks
from mechatron.library import electrical as el

R, C = 100.0, 1e-4            # tau = 10 ms
TAU = R * C


# -- the waveforms, written independently of the library ------------------------------------

def step(t, V, off, t0):
    return off + np.where(t >= t0, V, 0.0)


def ramp(t, V, dur, off, t0):
    return off + V * np.clip((t - t0) / dur, 0.0, 1.0)


def pulse(t, V, width, period, off, t0):
    s = np.mod(t - t0, period)
    return off + np.where((t >= t0) & (s < width * period), V, 0.0)


def trapezoid(t, V, rise, width, fall, period, off, t0):
    s = np.mod(t - t0, period)
    y = np.interp(s, [0, rise, rise + width, rise + width + fall, period], [0, 1, 1, 0, 0])
    return off + np.where(t >= t0, V * y, 0.0)


def exp_sine(t, V, f, ph, damp, off, t0):
    u = t - t0
    return off + np.where(t >= t0, V * np.exp(-damp * u) * np.sin(2 * np.pi * f * u + ph),
                          0.0)


CASES = [
    ("StepVoltage", dict(V=2.0, offset=-0.5, start_time=0.013),
     lambda t: step(t, 2.0, -0.5, 0.013), [0.013]),
    ("RampVoltage", dict(V=3.0, duration=0.02, offset=0.5, start_time=0.01),
     lambda t: ramp(t, 3.0, 0.02, 0.5, 0.01), [0.01, 0.03]),
    ("PulseVoltage", dict(V=5.0, width=0.3, period=0.01, offset=1.0, start_time=0.007),
     lambda t: pulse(t, 5.0, 0.3, 0.01, 1.0, 0.007),
     list(0.007 + np.arange(8) * 0.01) + list(0.007 + (np.arange(8) + 0.3) * 0.01)),
    ("TrapezoidVoltage", dict(V=4.0, rising=2e-3, width=3e-3, falling=1.5e-3, period=0.01,
                              offset=-1.0, start_time=0.004),
     lambda t: trapezoid(t, 4.0, 2e-3, 3e-3, 1.5e-3, 0.01, -1.0, 0.004),
     [0.004 + k * 0.01 + d for k in range(8) for d in (0, 2e-3, 5e-3, 6.5e-3)]),
    ("ExpSineVoltage", dict(V=3.0, f=60.0, phase=0.7, damping=30.0, offset=0.2,
                            start_time=0.011),
     lambda t: exp_sine(t, 3.0, 60.0, 0.7, 30.0, 0.2, 0.011), [0.011]),
]


def rc_with(source):
    m = mt.System("rc")
    m.add("src", source)
    r = m.add("r", el.Resistor(R=R))
    c = m.add("c", el.Capacitor(C=C))
    g = m.add("g", el.ElectricalReference())
    m.connect(source.p, r.p)
    m.connect(r.n, c.p)
    m.connect(source.n, c.n, g.port)
    return m


def scipy_rc(u, t_out, breaks):
    """dv/dt = (u(t) - v)/tau with u the NumPy waveform, integrated between breakpoints
    (so the reference never steps over a corner), v(0) = 0."""
    t_stop = t_out[-1]
    edges = np.unique(np.concatenate([[0.0], [b for b in breaks if 0 < b < t_stop],
                                      [t_stop]]))
    v, out = 0.0, np.empty_like(t_out)
    for a, b in zip(edges[:-1], edges[1:]):
        # the waveform on [a, b) continued to its ends (its value just inside)
        f = lambda t, y: (u(np.clip(t, a + 1e-12 * (b - a), b - 1e-12 * (b - a)))  # noqa: E731
                          - y) / TAU
        sel = (t_out >= a) & (t_out <= b)
        sol = solve_ivp(f, (a, b), [v], t_eval=t_out[sel], rtol=1e-11, atol=1e-13,
                        method="DOP853")
        out[sel] = sol.y[0]
        v = solve_ivp(f, (a, b), [v], rtol=1e-11, atol=1e-13, method="DOP853").y[0, -1]
    return out


@pytest.mark.parametrize("name,params,wave,breaks", CASES, ids=[c[0] for c in CASES])
def test_voltage_source_waveform_and_rc_response(name, params, wave, breaks):
    t_stop = 0.06
    t = np.linspace(0.0, t_stop, 601)
    # sample away from the breakpoints, where the waveform's value is unambiguous
    t = t[np.min(np.abs(t[:, None] - np.asarray(breaks)[None, :]), axis=1) > 1e-7]
    src = getattr(el, name)(**params)
    res = mt.simulate(rc_with(src), t_stop, t_out=t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["src.v"], wave(t), atol=1e-9)
    np.testing.assert_allclose(res["c.v"], scipy_rc(wave, t, breaks), atol=2e-7)
    # one event per breakpoint inside the run (the periodic ones also count the masked
    # edges before start_time, and the pulse its enable, as PWMVoltageSource)
    inside = [b for b in breaks if 0 < b < t_stop]
    assert res.stats.events["src"] >= len(inside)


def test_trapezoid_without_a_gap_is_a_triangle_wave():
    """rising + falling = period (no width, no gap): the triangle's mean over whole
    periods is V/2, and the RC response matches the SciPy model."""
    t0, P = 0.003, 4e-3
    src = el.TrapezoidVoltage(V=2.0, rising=1e-3, width=0.0, falling=3e-3, period=P,
                              start_time=t0)
    t = np.linspace(0.0, 0.05, 501)
    breaks = [t0 + k * P + d for k in range(13) for d in (0.0, 1e-3)]
    t = t[np.min(np.abs(t[:, None] - np.asarray(breaks)[None, :]), axis=1) > 1e-7]
    res = mt.simulate(rc_with(src), 0.05, t_out=t, rtol=1e-10, atol=1e-12)
    wave = lambda tt: trapezoid(tt, 2.0, 1e-3, 0.0, 3e-3, P, 0.0, t0)  # noqa: E731
    np.testing.assert_allclose(res["src.v"], wave(t), atol=1e-9)
    np.testing.assert_allclose(res["c.v"], scipy_rc(wave, t, breaks), atol=2e-7)


def test_table_voltage_interpolates_holds_and_jumps():
    rows = [(0.0, 1.0), (0.01, 3.0), (0.02, 3.0), (0.02, -1.0), (0.035, 0.5)]
    src = el.TableVoltage(table=rows, offset=0.25, start_time=0.005)
    t = np.array([0.0, 0.004, 0.0075, 0.012, 0.02, 0.0249, 0.02501, 0.03, 0.04, 0.05])
    res = mt.simulate(rc_with(src), 0.05, t_out=t, rtol=1e-10, atol=1e-12)
    # u = t - 0.005: 1 + 200 u up to u = 0.01, 3 up to 0.02, then -1 + 100 (u - 0.02)
    expect = 0.25 + np.array([1.0, 1.0, 1.0 + 200 * 0.0025, 1.0 + 200 * 0.007, 3.0, 3.0,
                              -1.0 + 100 * 1e-5, -1.0 + 100 * 0.005, 0.5, 0.5])
    np.testing.assert_allclose(res["src.v"], expect, atol=1e-9)
    # breakpoints: 0.005 (the rise starts), 0.015 (held), 0.025 (jump, then a rise),
    # 0.04 (the last value held)
    assert res.stats.events["src"] == 4
    def wave(tt):
        return 0.25 + np.interp(tt - 0.005, [0, 0.01, 0.02, 0.02 + 1e-15, 0.035],
                                [1, 3, 3, -1, 0.5])
    ref = scipy_rc(wave, res.t, [0.005, 0.015, 0.025, 0.04])
    np.testing.assert_allclose(res["c.v"], ref, atol=2e-7)


def test_table_is_checked():
    with pytest.raises(DataError, match="must not decrease"):
        el.TableVoltage(table=[(0, 0), (1, 1), (0.5, 2)])
    with pytest.raises(DataError, match="at least two rows"):
        el.TableCurrent(table=[(0, 0)])
    with pytest.raises(DataError, match="more than twice"):
        el.TableVoltage(table=[(0, 0), (1, 1), (1, 2), (1, 3)])


CURRENTS = [
    ("StepCurrent", dict(I=2e-3, offset=-1e-3, start_time=0.013),
     lambda t: step(t, 2e-3, -1e-3, 0.013), [0.013]),
    ("RampCurrent", dict(I=3e-3, duration=0.02, offset=0.5e-3, start_time=0.01),
     lambda t: ramp(t, 3e-3, 0.02, 0.5e-3, 0.01), [0.01, 0.03]),
    ("PulseCurrent", dict(I=5e-3, width=0.3, period=0.01, offset=1e-3, start_time=0.007),
     lambda t: pulse(t, 5e-3, 0.3, 0.01, 1e-3, 0.007),
     list(0.007 + np.arange(8) * 0.01) + list(0.007 + (np.arange(8) + 0.3) * 0.01)),
    ("TrapezoidCurrent", dict(I=4e-3, rising=2e-3, width=3e-3, falling=1.5e-3, period=0.01,
                              offset=-1e-3, start_time=0.004),
     lambda t: trapezoid(t, 4e-3, 2e-3, 3e-3, 1.5e-3, 0.01, -1e-3, 0.004),
     [0.004 + k * 0.01 + d for k in range(8) for d in (0, 2e-3, 5e-3, 6.5e-3)]),
    ("ExpSineCurrent", dict(I=3e-3, f=60.0, phase=0.7, damping=30.0, offset=0.2e-3,
                            start_time=0.011),
     lambda t: exp_sine(t, 3e-3, 60.0, 0.7, 30.0, 0.2e-3, 0.011), [0.011]),
    ("TableCurrent", dict(table=[(0.0, 0.0), (0.01, 2e-3), (0.03, -1e-3)], offset=1e-4,
                          start_time=0.005),
     lambda t: 1e-4 + np.interp(t - 0.005, [0, 0.01, 0.03], [0, 2e-3, -1e-3]),
     [0.005, 0.015, 0.035]),
]


@pytest.mark.parametrize("name,params,wave,breaks", CURRENTS, ids=[c[0] for c in CURRENTS])
def test_current_source_charges_a_capacitor_by_its_integral(name, params, wave, breaks):
    t_stop = 0.05
    m = mt.System("ic")
    src = m.add("src", getattr(el, name)(**params))
    c = m.add("c", el.Capacitor(C=C))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.n, c.p)           # the source pushes i out of n into the capacitor
    m.connect(src.p, c.n, g.port)
    t = np.linspace(0.0, t_stop, 51)[1:]
    t = t[np.min(np.abs(t[:, None] - np.asarray(breaks)[None, :]), axis=1) > 1e-7]
    res = mt.simulate(m, t_stop, t_out=t, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(res["src.i"], wave(t), atol=1e-12)
    pts = [b for b in breaks if 0 < b < t_stop]
    q = np.array([quad(wave, 0.0, tk, points=[b for b in pts if b < tk] or None,
                       limit=200, epsabs=1e-15, epsrel=1e-12)[0] for tk in t])
    np.testing.assert_allclose(res["c.v"], q / C, atol=1e-7)


def test_signal_ramp_with_a_duration_stops_rising():
    m = mt.System("ramp")
    r = m.add("r", blocks.Ramp(slope=2.0, start=0.5, initial=1.0, duration=1.5))
    r2 = m.add("r2", blocks.Ramp(slope=2.0, start=0.5, initial=1.0))     # no duration
    del r, r2
    t = np.linspace(0, 4, 41)
    res = mt.simulate(m, 4.0, t_out=t)
    np.testing.assert_allclose(res["r.y"], 1.0 + 2.0 * np.clip(t - 0.5, 0, 1.5), atol=1e-12)
    np.testing.assert_allclose(res["r2.y"], 1.0 + 2.0 * np.clip(t - 0.5, 0, None),
                               atol=1e-12)
    assert res.stats.events["r"] == 2 and res.stats.events["r2"] == 1

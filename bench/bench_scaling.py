"""Compile-time and simulation scaling with model size, and a hand-written SciPy baseline.

Two models built with ``mt.System`` for N = 10, 100, 1000, 10000:

* RC ladder: a DC voltage source (1 V, switched on at t = 0 onto discharged capacitors),
  then N sections of a series resistor (1 Ohm) and a capacitor (1 mF) to ground.
* Mass-spring chain: N masses (1 kg), each linked to the previous one (the first to a
  fixed reference) by a spring (1e4 N/m) and a damper (50 N*s/m) in parallel; the last
  mass starts displaced by 1 cm (start value of the last spring's deformation, priority
  high) and the chain rings down. (An initial displacement rather than a force step: a
  ``blocks.Step`` is a time event, which the explicitly requested CVODES misses, see
  README.)

For each: time to build the instance, compile time (wall clock, and per pass from
``report["timings"]``), equation and variable counts before/after, number of states, and
the wall time of ``mt.simulate`` over 1 s with CVODES (first call, which builds the
integrator, and a second call, profiled to show where the time goes; the largest size
runs once, and N = 10000 logs 101 output points instead of 1001). The growth exponent
``a`` of ``t ~ N**a`` is fitted between successive N.

The SciPy baseline integrates the RC ladder written by hand as a tridiagonal linear ODE
``C v' = (tridiagonal Laplacian) v / R + source`` with ``solve_ivp(method="BDF")`` and the
constant sparse Jacobian, same tolerances and output points.

Compile alone (``compile_scaling``): the RC ladder compiled once per N in a fresh
process each (N = 1000, and 10000 without ``--quick``; ``--large`` adds N = 100000, a
few minutes and about 4 GB), with the process CPU time of ``compile_model`` and of its
passes (``report["cpu_timings"]``; ``report["timings"]`` in wall clock), the peak
resident memory of the process (building the instance included) and the CPU
microseconds per flat equation.

Growth of the compile time per equation (``--growth [ROUNDS]``, issue 17: below 1.3x from
N = 1000 to N = 100000): rounds of one N = 100000 compile and ten N = 1000 compiles, each
in a fresh process, in turn. On a shared machine the CPU time of the same work moves
between two levels, in spells of a few seconds: a plain Python loop runs 1.6-1.8x slower
in a slow spell (``machine_spells`` prints the share of slow loops before and after).
The compile of N = 1000 (cache-resident, bound by execution) slows about as much; that
of N = 100000 (bound by memory) much less. So the ratio of the *means* flatters when the
machine is busy, and the growth is read on the *minima*, the runs nearest to a calm
machine, taken over equally many runs of each size: the fastest of the N = 100000
compiles against the fastest N = 1000 compile expected among as many (``expected_min``:
the mean over every choice of that many of its runs). Even on a calm machine the short
N = 1000 compiles spread by 5 % either way and the long ones by a few tenths of a
percent, so the fastest of thirty lies further into its spread than the fastest of
three: the ratio of the plain minima (printed beside) reads about 0.1 high. Means and
medians are printed beside it, with every run and its passes, user and kernel time
apart, what one page fault costs the machine before and after, and what each fault of
the large compiles cost the kernel (more where the host must back memory the machine
has not touched lately); each pass's median per equation at both sizes is printed with
its growth (where the growth is). Its peer,
run beside each compile in a fresh process: the same structural passes written by hand
on NumPy/SciPy arrays (``structure_on_arrays``: flattening, connection sets, alias
elimination, matching, BLT; no symbolic expressions), with its own growth and the
compile's cost over it.

Compile work counted, not timed (``--counted``): the instructions and the data-cache
misses of compiling the RC ladder at N = 1000 and N = 10000, per flat equation, counted by
valgrind's cachegrind on a fixed simulated cache (32 KiB first level, 32 MiB last level,
as on the machine the goals were set on), so the same on any machine and under any load.
Each count is a compile's process less a process that builds the same ladder and stops
there. The instructions per equation show whether the work per equation grows; the
last-level misses per equation show what the time measures can only suggest, how much
more of the compile runs out of memory at the larger size. Cachegrind models no
prefetcher: a sequential scan counts as misses that a real processor mostly hides. Needs
valgrind (``apt-get install valgrind``); about 10 minutes.

``--quick`` skips N = 10000. Run: ``python bench/bench_scaling.py [--quick] [--large]``,
``python bench/bench_scaling.py --growth [ROUNDS]``, ``python bench/bench_scaling.py
--counted [--passes]`` (``--passes``: each pass counted apart, about 35 minutes).
"""

from __future__ import annotations

import gc
import json
import math
import mmap
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

import _common  # noqa: F401  (import path)
from _common import (clock, growth_exponent, log, logging_alternative, main, peak_rss_mb,
                     profiled, ratio, repeat, summary)

import numpy as np
import scipy.sparse as sp
from scipy.integrate import solve_ivp
from scipy.sparse import csgraph

import mechatron as mt
from mechatron.compiler import heap
from mechatron.library import electrical as el
from mechatron.library import translational as tr

SIZES = (10, 100, 1000, 10000)
T_STOP = 1.0
RTOL, ATOL = 1e-6, 1e-8
N_OUT = 1001
N_OUT_LARGE = 101      # output points when N = 10000 (see _grid)
GOALS = {1000: 2.0, 10000: 20.0}   # compile-time goals of the project, s
COMPILE_CPU_GOALS = {1000: 0.5, 10000: 5.0, 100000: 60.0}   # issue 17, CPU s
LARGE = 100000

# RC ladder and chain parameters
R_SERIES, C_SHUNT, V_SOURCE = 1.0, 1e-3, 1.0
MASS, SPRING, DAMPER, X_LAST = 1.0, 1e4, 50.0, 0.01


# -- models ---------------------------------------------------------------------------------
def rc_ladder(n: int) -> mt.System:
    """Voltage source, then ``n`` sections of series resistor + capacitor to ground."""
    m = mt.System(f"rc_ladder_{n}")
    src = m.add("src", el.DCVoltageSource(V=V_SOURCE))
    gnd = m.add("gnd", el.ElectricalReference())
    m.connect(src.n, gnd.port)
    node = src.p
    for k in range(n):
        r = m.add(f"r{k}", el.Resistor(R=R_SERIES))
        c = m.add(f"c{k}", el.Capacitor(C=C_SHUNT))
        m.connect(node, r.p)
        m.connect(r.n, c.p)
        m.connect(c.n, gnd.port)
        node = r.n
    return m


def mass_spring_chain(n: int) -> mt.System:
    """``n`` masses in a chain of springs and dampers from a fixed reference; the last mass
    starts displaced by ``X_LAST``."""
    m = mt.System(f"mass_spring_chain_{n}")
    ref = m.add("ref", tr.TranslationalReference())
    prev = ref.port
    for k in range(n):
        mass = m.add(f"m{k}", tr.Mass(m=MASS))
        start = {"x": X_LAST} if k == n - 1 else {}
        spring = m.add(f"k{k}", tr.TranslationalSpring(k=SPRING, **start))
        damper = m.add(f"b{k}", tr.TranslationalDamper(b=DAMPER))
        m.connect(mass.port, spring.A, damper.A)
        m.connect(spring.B, damper.B, prev)
        prev = mass.port
    return m


MODELS = {"rc_ladder": (rc_ladder, lambda n: [f"c{k}.v" for k in range(n)]),
          "mass_spring_chain": (mass_spring_chain, lambda n: [f"m{k}.v" for k in range(n)])}


# -- the SciPy baseline ---------------------------------------------------------------------
def scipy_rc_ladder(n: int, t_out: np.ndarray, repeats: int) -> dict:
    """The RC ladder by hand: ``v' = (A v + b)``, A tridiagonal, BDF with sparse Jacobian."""
    g = 1.0 / (R_SERIES * C_SHUNT)
    main_diag = np.full(n, -2.0 * g)
    main_diag[-1] = -g                       # the last capacitor has one resistor only
    off = np.full(n - 1, g)
    A = sp.diags([off, main_diag, off], [-1, 0, 1], format="csc")
    b = np.zeros(n)
    b[0] = g * V_SOURCE

    def rhs(t, v):
        return A @ v + b

    def once():
        return solve_ivp(rhs, (0.0, T_STOP), np.zeros(n), method="BDF", jac=A,
                         t_eval=t_out, rtol=RTOL, atol=ATOL)

    sol, times = repeat(once, repeats)
    return {"time": summary(times), "success": bool(sol.success), "nfev": sol.nfev,
            "njev": sol.njev, "nlu": sol.nlu, "final": sol.y[:, -1]}


# -- one size -------------------------------------------------------------------------------
def _grid(n: int) -> np.ndarray:
    # Every logged variable is evaluated at every output point: at N = 10000 that is
    # 1.2e5 variables x 1001 points (1 GB as float64, several GB on the way through
    # casadi.DM), so the largest size logs fewer points.
    return np.linspace(0.0, T_STOP, N_OUT if n < 10000 else N_OUT_LARGE)


def _compile_repeats(n: int, quick: bool) -> int:
    if n <= 100:
        return 3 if quick else 5
    return 1 if quick or n >= 10000 else 3


def measure(kind: str, n: int, *, simulate_twice: bool = True, compiles: int = 1) -> dict:
    """Build and compile ``compiles`` times (fresh instance each), keep the run with the
    median wall time, and simulate its compiled model."""
    build, observed = MODELS[kind]
    runs = []
    for _ in range(compiles):
        gc.collect()
        model, t_build = clock(build, n)
        cpu = time.process_time()
        cm, t_compile = clock(mt.compile_model, model)
        runs.append((t_compile, time.process_time() - cpu, t_build, cm))
        del model
    runs.sort(key=lambda r: r[0])
    t_compile, cpu_compile, t_build, cm = runs[len(runs) // 2]
    rep = cm.report
    log(f"{kind} N={n}: compile {t_compile:.3f} s (cpu {cpu_compile:.3f} s; "
        f"{', '.join(f'{k} {v:.3f}' for k, v in rep.get('timings', {}).items())})")
    grid = _grid(n)
    row = {"N": n, "build_s": t_build, "compile_s": t_compile,
           "compile_cpu_s": cpu_compile, "compile_min_s": runs[0][0],
           "compile_repeats": len(runs),
           "passes_s": dict(rep.get("timings", {})),
           "equations": rep.get("equations"), "variables": rep.get("variables"),
           "n_states": len(cm.state_names), "aliases_eliminated": rep.get("aliases_eliminated"),
           "logged_variables": len(cm.names), "output_points": grid.size}

    def sim():
        return mt.simulate(cm, T_STOP, solver="cvodes", rtol=RTOL, atol=ATOL, t_out=grid)

    if simulate_twice:
        _, row["simulate_first_s"] = clock(sim)
        gc.collect()
        res, row["simulate_second_s"], where = profiled(sim)
    else:
        res, row["simulate_first_s"], where = profiled(sim)
    row["simulate_profile_s"] = where
    row["logging_by_buffer"] = logging_alternative(cm, res, grid)
    st = res.stats
    row["solver_stats"] = {"solver": st.solver, "steps": st.steps,
                           "rejected_steps": st.rejected_steps, "rhs_evals": st.rhs_evals,
                           "jac_evals": st.jac_evals, "events": st.events}
    final = np.array([res[name][-1] for name in observed(n)])
    log(f"{kind} N={n}: simulate first {row['simulate_first_s']:.3f} s"
        + (f", second {row['simulate_second_s']:.3f} s" if simulate_twice else "")
        + f"; integrate_variable {where['integrate_variable_s']:.3f} s "
          f"(CVODES call {where['solver_call_s']:.3f} s), "
          f"Function.map {where['casadi_Function_map_s']:.3f} s, "
          f"DM->numpy {where['dm_to_numpy_s']:.3f} s")
    return row, final, grid


def _cpu_of(fn, *args) -> tuple:
    """``fn(*args)`` and what it took of this process: CPU seconds (`time.process_time`),
    user and system (kernel) seconds, and minor page faults (the kernel's share is
    mostly first touches of new memory)."""
    before, cpu = resource.getrusage(resource.RUSAGE_SELF), time.process_time()
    out = fn(*args)
    cpu = time.process_time() - cpu
    after = resource.getrusage(resource.RUSAGE_SELF)
    return out, {"cpu_s": cpu, "user_s": after.ru_utime - before.ru_utime,
                 "system_s": after.ru_stime - before.ru_stime,
                 "minor_page_faults": after.ru_minflt - before.ru_minflt}


def compile_once(n: int) -> dict:
    """Build and compile the RC ladder of ``n`` sections once, in this process: CPU and
    wall time of ``compile_model``, its passes, and the process's peak resident memory.
    A ladder of 2 sections is compiled first: the modules the compiler imports on first
    use are then loaded, and not counted."""
    mt.compile_model(rc_ladder(2))
    gc.collect()
    model, t_build = clock(rc_ladder, n)
    before = heap.arena_counts() or {}
    (cm, t_compile), took = _cpu_of(clock, mt.compile_model, model)
    after = heap.arena_counts() or {}
    cpu = took.pop("cpu_s")
    rep = cm.report
    flat = (rep.get("equations") or {}).get("flat") or 0
    # Python's arenas (compiler/heap.py): asked for by the compile, and taken again from
    # those it handed back (none where the compile does not keep them)
    arenas = {k: after.get(k, 0) - before.get(k, 0) for k in ("asked", "reused")}
    return {"N": n, "build_s": t_build, "compile_s": t_compile, "compile_cpu_s": cpu,
            "arenas_asked": arenas["asked"], "arenas_reused": arenas["reused"],
            "passes_s": dict(rep.get("timings", {})),
            "passes_cpu_s": dict(rep.get("cpu_timings", {})), "equations_flat": flat,
            "states": len(cm.state_names),
            "us_per_equation": 1e6 * cpu / flat if flat else None,
            **took, "peak_rss_MB": peak_rss_mb()}


# -- the array peer of the growth -----------------------------------------------------
#: the variables of a two-pin component, in the compiler's order of declaration
_TWO_PIN_KEYS = ("v", "i", "p.v", "p.i", "n.v", "n.i")


def structure_on_arrays(n: int) -> dict:
    """The structural work of compiling the RC ladder of ``n`` sections, written by hand on
    NumPy/SciPy arrays: the peer of the compile's growth per equation (``--growth``).

    Flattening (every variable's name, each class's equations instantiated over its
    instances by broadcasting, as integer triplets), connection sets (connected
    components of the connect graph; across variables equal to the set's first member,
    one flow sum per set), alias elimination (rows of two entries of coefficient +-1
    joined by connected components, each variable's sign to its representative
    propagated level by level; a variable fixed to a constant, the ground's voltage,
    becomes known), the incidence of what is left, its maximum matching (Hopcroft-Karp)
    and its block-lower-triangular blocks (strongly connected components). No symbolic
    expression is formed: it is a lower bound on what those passes cost per equation,
    and on how that cost grows with the model. The counts it returns equal the
    compiler's (``tests/test_bench.py`` checks them)."""
    v_, i_, pv, pi_, nv, ni = range(6)
    ncomp = 2 * n + 1                   # the source, resistors 1..n, capacitors n+1..2n
    gnd = 6 * ncomp                     # the ground's port: its v, then its i
    n_var = gnd + 2
    n_all = n_var + n                   # and each capacitor's der(v), an unknown
    paths = ["src"] + [f"r{k}" for k in range(n)] + [f"c{k}" for k in range(n)]
    names = [f"{path}.{key}" for path in paths for key in _TWO_PIN_KEYS]
    names += ["gnd.port.v", "gnd.port.i"]
    base = 6 * np.arange(ncomp)
    rows: list = []
    cols: list = []
    coef: list = []
    n_eq = 0

    def add(bases, template, extra=None):
        """Each equation of ``template`` (its terms: slot and coefficient, nan for a
        parameter; slot -1 is ``extra``) once per instance in ``bases``."""
        nonlocal n_eq
        for eq in template:
            for slot, c in eq:
                rows.append(n_eq + np.arange(bases.size))
                cols.append(bases + slot if slot >= 0 else extra)
                coef.append(np.full(bases.size, c))
            n_eq += bases.size

    # v == p.v - n.v, p.i + n.i == 0, i == p.i for every two-pin component
    add(base, [((v_, 1.0), (pv, -1.0), (nv, 1.0)), ((pi_, 1.0), (ni, 1.0)),
               ((i_, 1.0), (pi_, -1.0))])
    add(base[:1], [((v_, 1.0),)])                      # v == V (a parameter)
    add(base[1:n + 1], [((v_, 1.0), (i_, np.nan))])    # v == R i
    add(base[n + 1:], [((i_, -1.0), (-1, np.nan))], extra=n_var + np.arange(n))
    constant = n_eq                                     # gnd.port.v == 0
    rows.append(np.array([n_eq]))
    cols.append(np.array([gnd]))
    coef.append(np.ones(1))
    n_eq += 1
    # the connects, port to port (a port by its first variable, v; its i follows)
    r, c = base[1:n + 1], base[n + 1:]
    a = np.concatenate([[base[0] + 2], [base[0] + 4], r + 4, c + 4, r[:-1] + 4])
    b = np.concatenate([[r[0] + 2], [gnd], c + 2, np.full(n, gnd), r[1:] + 2])
    ports, at = np.unique(np.concatenate([a, b]), return_inverse=True)
    m = ports.size
    graph = sp.coo_matrix((np.ones(a.size), (at[:a.size], at[a.size:])), shape=(m, m))
    n_sets, label = csgraph.connected_components(graph, directed=False)
    order = np.lexsort((ports, label))              # each set's members by port
    first = np.r_[True, label[order][1:] != label[order][:-1]]
    lead = np.maximum.accumulate(np.where(first, np.arange(m), 0))
    member, leader = ports[order], ports[order][lead]
    others = int((~first).sum())                    # across: member.v == first.v
    rows += [n_eq + np.arange(others)] * 2
    cols += [member[~first], leader[~first]]
    coef += [np.ones(others), -np.ones(others)]
    n_eq += others
    rows.append(n_eq + label[order])                # through: one sum per set
    cols.append(member + 1)
    coef.append(np.ones(m))
    n_eq += n_sets
    rows, cols, coef = map(np.concatenate, (rows, cols, coef))
    n_flat = n_eq
    # alias elimination
    unit = np.isfinite(coef) & (np.abs(coef) == 1.0)
    pair_rows = np.flatnonzero((np.bincount(rows, minlength=n_eq) == 2)
                               & (np.bincount(rows, unit, minlength=n_eq) == 2))
    picked = np.isin(rows, pair_rows)
    o = np.argsort(rows[picked], kind="stable")
    pair = cols[picked][o].reshape(-1, 2)
    pk = coef[picked][o].reshape(-1, 2)
    joined = sp.coo_matrix((np.ones(len(pair)), (pair[:, 0], pair[:, 1])),
                           shape=(n_all, n_all))
    _, cls = csgraph.connected_components(joined, directed=False)
    rep = np.full(cls.max() + 1, n_all)
    np.minimum.at(rep, cls, np.arange(n_all))       # the lowest variable represents
    rep = rep[cls]
    sign = np.where(rep == np.arange(n_all), 1.0, 0.0)
    ratio = -pk[:, 0] * pk[:, 1]                     # a x + b y == 0: x == ratio y
    x, y = pair[:, 0], pair[:, 1]
    while True:
        to_x = (sign[x] == 0) & (sign[y] != 0)
        to_y = (sign[y] == 0) & (sign[x] != 0)
        if not (to_x.any() or to_y.any()):
            break
        sign[x[to_x]] = ratio[to_x] * sign[y[to_x]]
        sign[y[to_y]] = ratio[to_y] * sign[x[to_y]]
    known = np.zeros(n_all, dtype=bool)
    known[rep[gnd]] = True
    keep = np.ones(n_eq, dtype=bool)
    keep[pair_rows] = False
    keep[constant] = False
    kept = keep[rows]
    kr, kc = rows[kept], rep[cols[kept]]
    live = ~known[kc]
    kr, kc = kr[live], kc[live]
    equations, kr = np.unique(kr, return_inverse=True)
    # the unknowns: representatives that are neither states (the capacitors' v) nor known
    state = np.zeros(n_all, dtype=bool)
    state[rep[base[n + 1:] + v_]] = True
    unknown = (rep == np.arange(n_all)) & ~state & ~known
    column = np.full(n_all, -1)
    column[unknown] = np.arange(int(unknown.sum()))
    inside = column[kc] >= 0
    incidence = sp.csr_matrix((np.ones(int(inside.sum())), (kr[inside], column[kc[inside]])),
                              shape=(equations.size, int(unknown.sum())))
    incidence.sum_duplicates()
    matched = csgraph.maximum_bipartite_matching(incidence, perm_type="column")
    if (matched < 0).any():
        raise RuntimeError("structure_on_arrays: structurally singular")
    # equation e depends on equation f when e holds the unknown matched to f
    row_of = np.empty(incidence.shape[1], dtype=np.int64)
    row_of[matched] = np.arange(incidence.shape[0])
    holder = np.repeat(np.arange(incidence.shape[0]), np.diff(incidence.indptr))
    depends = sp.csr_matrix((np.ones(incidence.nnz), (holder, row_of[incidence.indices])),
                            shape=(incidence.shape[0],) * 2)
    blocks, _ = csgraph.connected_components(depends, directed=True, connection="strong")
    return {"equations_flat": n_flat, "variables_flat": len(names),
            "after_alias": int(equations.size), "unknowns": int(incidence.shape[1]),
            "blocks": int(blocks)}


def arrays_once(n: int) -> dict:
    """`structure_on_arrays` of ``n`` sections in this process, after one of 10 (imports
    and first calls), with its CPU time per flat equation (user and kernel)."""
    structure_on_arrays(10)
    gc.collect()
    out, took = _cpu_of(structure_on_arrays, n)
    return {"N": n, **out, **took,
            "us_per_equation": 1e6 * took["cpu_s"] / out["equations_flat"]}


def _fresh(flag: str, n: int) -> dict:
    """This script run with ``flag n`` (``--compile-one``, ``--arrays-one``) in a fresh
    process: the JSON of its last line."""
    done = subprocess.run([sys.executable, __file__, flag, str(n)],
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def compile_scaling(sizes: list[int], fresh: bool = True) -> dict:
    """``compile_once`` per N, each in a new process when ``fresh`` (so the peak memory
    is that N's), with the growth of the time per equation between sizes."""
    rows = []
    for n in sizes:
        if fresh:
            row = _fresh("--compile-one", n)
        else:
            row = compile_once(n)
        log(f"rc_ladder N={n} compile alone: cpu {row['compile_cpu_s']:.3f} s "
            f"(system {row['system_s']:.3f} s, {row['minor_page_faults']} page faults, "
            f"{row['arenas_reused']} of {row['arenas_asked']} arenas reused), "
            f"{row['us_per_equation']:.1f} us/equation, peak {row['peak_rss_MB']:.0f} MB")
        rows.append(row)
    first = rows[0]["us_per_equation"] if rows else None
    for row in rows:
        row["us_per_equation_over_smallest"] = ratio(row["us_per_equation"], first)
        goal = COMPILE_CPU_GOALS.get(row["N"])
        row["goal_cpu_s"] = goal
        row["met"] = row["compile_cpu_s"] < goal if goal else None
    return {"rows": rows, "fresh_process": fresh,
            "growth_exponents": _exponents(rows, lambda r: r["compile_cpu_s"])}


def machine_spells(seconds: float = 10.0) -> dict:
    """How steady this machine's CPU is: a fixed Python loop timed over and over for
    ``seconds``; the share of the loops that took over 1.3x the fastest, and the slowest
    over the fastest (1.0 on a machine of its own)."""
    n = 100_000
    start, times = time.perf_counter(), []
    while time.perf_counter() - start < seconds:
        t = time.process_time()
        s = 0
        for i in range(n):
            s += i
        times.append(time.process_time() - t)
    fastest = min(times)
    return {"loops": len(times), "fastest_ms": 1e3 * fastest,
            "slow_share": sum(t > 1.3 * fastest for t in times) / len(times),
            "slowest_over_fastest": max(times) / fastest,
            "median_over_fastest": statistics.median(times) / fastest}


def fresh_page_cost(mb: int = 256) -> dict:
    """What the first touch of fresh memory costs this process: an anonymous mapping of
    ``mb`` MiB, one byte written in each 4 KiB page (one page fault each, as Python's
    arenas take theirs; no huge pages, which the kernel gives such a mapping only on
    request), in CPU microseconds per page, user and kernel, and the page faults. On a
    virtual machine the host may back the guest's memory only when it is first touched
    (and take back what the guest frees), which makes a fault several times dearer than
    on bare metal; a large compile takes hundreds of thousands of them."""
    pages = mb * 256
    region = mmap.mmap(-1, pages * 4096)
    view = np.frombuffer(region, dtype=np.uint8)
    _, took = _cpu_of(view.__setitem__, slice(None, None, 4096), 1)
    del view
    region.close()
    return {"MiB": mb, "us_per_page": 1e6 * (took["user_s"] + took["system_s"]) / pages,
            "system_us_per_page": 1e6 * took["system_s"] / pages,
            "page_faults": took["minor_page_faults"]}


def expected_min(values: list[float], k: int) -> float:
    """The expected minimum of ``k`` of ``values`` drawn without replacement (every
    choice of ``k`` equally likely): the fastest run of a sample of ``k``, to compare
    with the fastest of ``k`` runs of another kind."""
    v = sorted(values)
    n = len(v)
    if not 1 <= k <= n:
        raise ValueError(f"expected_min: {k} draws from {n} values")
    # v[i] is the minimum of the choices that take it and k - 1 of the n - 1 - i above
    return sum(x * math.comb(n - 1 - i, k - 1) for i, x in enumerate(v)) / math.comb(n, k)


def _growth_of(small: list[float], large: list[float]) -> dict:
    """The growth from the runs ``small`` to the runs ``large`` (figures per equation):
    the ratio of their means, medians and minima, and ``min_equal_draws``, the fastest
    large run over the fastest small run expected among as many (`expected_min`)."""
    return {"mean": statistics.mean(large) / statistics.mean(small),
            "median": statistics.median(large) / statistics.median(small),
            "min": min(large) / min(small),
            "min_equal_draws": min(large) / expected_min(small, len(large))}


def compile_growth(rounds: int = 4, small: int = 1000, large: int = LARGE,
                   per_round: int = 10) -> dict:
    """The growth of the compile CPU time per flat equation from ``small`` to ``large``:
    ``rounds`` rounds of one ``large`` and ``per_round`` ``small`` compiles, each in a
    fresh process (see the module's docstring for why the minima are compared), each
    followed by its peer (`structure_on_arrays`, in a fresh process too)."""
    spells = [machine_spells()]
    pages = [fresh_page_cost()]
    runs: dict[int, list[dict]] = {small: [], large: []}
    peer: dict[int, list[dict]] = {small: [], large: []}
    for k in range(rounds):
        for n in [large] + [small] * per_round:
            runs[n].append(_fresh("--compile-one", n))
            peer[n].append(_fresh("--arrays-one", n))
        log(f"round {k + 1} of {rounds}: N={large} "
            f"{runs[large][-1]['us_per_equation']:.1f} us/equation, N={small} "
            + " ".join(f"{r['us_per_equation']:.1f}" for r in runs[small][-per_round:]))
    spells.append(machine_spells())
    pages.append(fresh_page_cost())
    per = {n: [r["us_per_equation"] for r in rs] for n, rs in runs.items()}
    # the same split into the process's user and kernel time (the kernel's: page faults,
    # whose cost depends on the host as much as on the compile; see fresh_page_cost)
    split = {n: {part: [1e6 * r[f"{part}_s"] / r["equations_flat"] for r in rs]
                 for part in ("user", "system")} for n, rs in runs.items()}
    stats = {str(n): {"us_per_equation": v, "mean": statistics.mean(v),
                      "median": statistics.median(v), "min": min(v),
                      "peak_rss_MB": max(r["peak_rss_MB"] for r in runs[n]),
                      "user_us_per_equation": split[n]["user"],
                      "system_us_per_equation": split[n]["system"],
                      "page_faults_per_equation": [
                          r["minor_page_faults"] / r["equations_flat"] for r in runs[n]],
                      "arenas_reused_of_asked": [
                          (r["arenas_reused"], r["arenas_asked"]) for r in runs[n]],
                      # each run's passes, us per flat equation
                      "passes_us_per_equation": [
                          {k: 1e6 * t / r["equations_flat"]
                           for k, t in r["passes_cpu_s"].items()} for r in runs[n]]}
             for n, v in per.items()}
    a, b = stats[str(small)], stats[str(large)]
    # `met` reads the minima over equally many runs of each size (see the module's
    # docstring)
    growth = _growth_of(per[small], per[large])
    # user time alone: the compiler's own growth, without the kernel's share of the page
    # faults (the kernel splits a process's CPU time into user and system by samples:
    # the split of one short run is off by a few percent, hence the medians beside)
    growth_user = _growth_of(split[small]["user"], split[large]["user"])
    # what a page fault of the large compiles cost the kernel: the probe's fresh page
    # (fresh_page_cost) is a page the host already backs; a compile that outgrows the
    # memory the machine touched lately also waits for the host to back its pages
    per_fault = [1e6 * r["system_s"] / r["minor_page_faults"] for r in runs[large]
                 if r["minor_page_faults"]]
    # the peer: the same structural passes on arrays, without symbolic expressions
    on_arrays = {str(n): {"us_per_equation": [r["us_per_equation"] for r in rs],
                          "min": min(r["us_per_equation"] for r in rs),
                          "median": statistics.median(r["us_per_equation"] for r in rs)}
                 for n, rs in peer.items()}
    pa, pb = on_arrays[str(small)], on_arrays[str(large)]
    peer_growth = _growth_of(pa["us_per_equation"], pb["us_per_equation"])
    log(f"peer on arrays (structure without symbolic expressions): minima "
        f"{pa['min']:.2f} and {pb['min']:.2f} us/equation, growth {peer_growth['min']:.3f} "
        f"(medians {peer_growth['median']:.3f}); the compile costs "
        f"{a['min'] / pa['min']:.0f} and {b['min'] / pb['min']:.0f} times as much")
    log(f"growth per equation N={small} to {large}: minima over equally many runs "
        f"{growth['min_equal_draws']:.3f} (goal < 1.3), plain minima {growth['min']:.3f}, "
        f"medians {growth['median']:.3f}, means {growth['mean']:.3f}; "
        f"slow share of the machine {spells[0]['slow_share']:.2f}, "
        f"{spells[1]['slow_share']:.2f}; user time alone: minima over equally many runs "
        f"{growth_user['min_equal_draws']:.3f}, plain {growth_user['min']:.3f}, "
        f"medians {growth_user['median']:.3f}; a fresh page "
        f"{pages[0]['us_per_page']:.2f} and {pages[1]['us_per_page']:.2f} us, a fault of "
        f"the N={large} compiles "
        + "/".join(f"{c:.1f}" for c in per_fault) + " us")
    # where the growth is: each pass's median per equation at both sizes
    per_pass = {key: {str(n): statistics.median(p[key] for p in stats[str(n)][
                    "passes_us_per_equation"]) for n in (small, large)}
                for key in a["passes_us_per_equation"][0]}
    log(f"per pass, medians, us/equation N={small} -> {large}: " + ", ".join(
        f"{key} {v[str(small)]:.2f} -> {v[str(large)]:.2f} "
        f"({v[str(large)] / v[str(small)]:.2f}x)" for key, v in per_pass.items()
        if v[str(small)] > 0))
    return {"small": small, "large": large, "rounds": rounds, "per_round": per_round,
            "sizes": stats, "growth": growth, "growth_user": growth_user, "goal": 1.3,
            "passes_median_us_per_equation": per_pass,
            "met": growth["min_equal_draws"] < 1.3, "machine_spells_before_after": spells,
            "fresh_page_cost_before_after": pages,
            "kernel_us_per_fault_large": per_fault,
            "peer_structure_on_arrays": {"sizes": on_arrays, "growth": peer_growth,
                                         "compile_over_peer_min": {
                                             str(small): a["min"] / pa["min"],
                                             str(large): b["min"] / pb["min"]}}}


def run_growth(quick: bool = False, rounds: int = 4) -> dict:
    """Growth of the compile time per equation, N = 1000 to 100000 (issue 17)."""
    return {"benchmark": "scaling_growth",
            "compile_growth": compile_growth(rounds=1 if quick else rounds)}


#: the simulated caches of ``--counted`` (size, associativity, line: valgrind's syntax)
COUNTED_CACHES = {"I1": "32768,8,64", "D1": "32768,8,64", "LL": "33554432,16,64"}
#: cachegrind's events, read from its output file, and what ``--counted`` reports
COUNTED_EVENTS = {"Ir": "instructions", "D1mr": "first_level_read_misses",
                  "DLmr": "last_level_read_misses", "DLmw": "last_level_write_misses"}


#: where a ``--counted --passes`` process stops: after building the ladder, after each of
#: these passes of `mechatron.compiler.pipeline` (the name it calls), or at the end
COUNTED_STOPS = {"flatten": "flatten", "dimensions": "_check_dimensions",
                 "alias": "eliminate_aliases", "structure": "lower"}


def counted_one(n: int, stop: str) -> None:
    """What ``--counted`` runs under cachegrind: build the RC ladder of ``n`` sections
    (after a ladder of 2 compiled, as in `compile_once`); unless ``stop`` is "build",
    compile it, to the end ("compile") or until the pass ``stop`` of `COUNTED_STOPS`
    returns; print the flat equations; leave without tearing down (freeing the model at
    exit is neither side's work)."""
    from mechatron.compiler import pipeline

    if stop not in ("build", "compile", *COUNTED_STOPS):
        raise ValueError(f"--counted-one: unknown stop {stop!r}; one of build, compile, "
                         + ", ".join(COUNTED_STOPS))
    mt.compile_model(rc_ladder(2))
    model = rc_ladder(n)
    gc.collect()

    def leave(flat: int = 0) -> None:
        print(json.dumps({"N": n, "stop": stop, "equations_flat": flat}), flush=True)
        os._exit(0)

    if stop in COUNTED_STOPS:
        name = COUNTED_STOPS[stop]
        original = getattr(pipeline, name)

        def then_leave(*args, **kwargs):
            original(*args, **kwargs)
            leave()
        setattr(pipeline, name, then_leave)
    leave(mt.compile_model(model).report["equations"]["flat"] if stop != "build" else 0)


def cachegrind_totals(path: str | os.PathLike) -> dict[str, int]:
    """The totals of a cachegrind output file by event name (its ``events:`` line and
    its ``summary:`` or ``totals:`` line)."""
    events = totals = None
    with open(path) as text:
        for line in text:
            if line.startswith("events:"):
                events = line.split()[1:]
            elif line.startswith(("summary:", "totals:")):
                totals = [int(v) for v in line.split()[1:]]
    if events is None or totals is None or len(events) != len(totals):
        raise ValueError(f"{path}: not a complete cachegrind output file (no events or "
                         "totals line)")
    return dict(zip(events, totals))


def _cachegrind(n: int, stop: str, folder: str) -> tuple[dict, dict]:
    """One `counted_one` process under cachegrind: (its JSON line, its totals)."""
    out = os.path.join(folder, f"cg.{n}.{stop}")
    cmd = ["valgrind", "--tool=cachegrind", "--cache-sim=yes",
           *[f"--{k}={v}" for k, v in COUNTED_CACHES.items()],
           f"--cachegrind-out-file={out}", sys.executable, __file__,
           "--counted-one", str(n), stop]
    # string hashing seeded alike in every process: the same dictionary layouts; one
    # BLAS thread: OpenBLAS's idle threads spin at start-up and exit, 250-300 M
    # instructions that vary by 20 M or more from one process to the next
    env = {**os.environ, "PYTHONHASHSEED": "0", "OPENBLAS_NUM_THREADS": "1",
           "OMP_NUM_THREADS": "1"}
    done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        tail = "\n".join(done.stderr.strip().splitlines()[-5:])
        raise RuntimeError(f"cachegrind run of N={n} ({stop}) failed "
                           f"({done.returncode}):\n{tail}")
    return json.loads(done.stdout.strip().splitlines()[-1]), cachegrind_totals(out)


def compile_counted(sizes: tuple[int, ...] = (1000, 10000), passes: bool = False,
                    runner=None) -> dict:
    """Instructions and cache misses of compiling the RC ladder, per flat equation, at
    each of ``sizes``, and their growth from the first size to each other (see the
    module's docstring); with ``passes``, also of each pass (`COUNTED_STOPS`, then
    the rest of the compile): the differences of processes stopped after each.
    ``runner(n, stop, folder)`` replaces the cachegrind run (tests)."""
    if runner is None:
        if shutil.which("valgrind") is None:
            log("counted compile work: valgrind is not installed (apt-get install "
                "valgrind); skipped")
            return {"skipped": "valgrind is not installed"}
        runner = _cachegrind
    stops = ["build", *(COUNTED_STOPS if passes else ()), "compile"]
    jobs = [(n, stop) for n in sizes for stop in stops]
    with tempfile.TemporaryDirectory() as folder, \
            ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        done = dict(zip(jobs, pool.map(lambda job: runner(*job, folder), jobs)))

    def per_equation(after: dict, before: dict, flat: int) -> dict:
        return {f"{key}_per_equation": (after[event] - before[event]) / flat
                for event, key in COUNTED_EVENTS.items()}

    rows = []
    for n in sizes:
        flat = done[(n, "compile")][0]["equations_flat"]
        row = {"N": n, "equations_flat": flat,
               **per_equation(done[(n, "compile")][1], done[(n, "build")][1], flat)}
        if passes:      # each pass: its stop less the one before
            row["passes"] = {
                ("rest" if stop == "compile" else stop):
                per_equation(done[(n, stop)][1], done[(n, earlier)][1], flat)
                for earlier, stop in zip(stops, stops[1:])}
        rows.append(row)
        log(f"rc_ladder N={n} compile, counted: "
            f"{row['instructions_per_equation'] / 1e3:.1f}k instructions, "
            f"{row['first_level_read_misses_per_equation']:.0f} first-level read misses, "
            f"{row['last_level_read_misses_per_equation']:.1f} + "
            f"{row['last_level_write_misses_per_equation']:.1f} last-level read + write "
            "misses per equation")
        for name, part in row.get("passes", {}).items():
            log(f"  {name}: {part['instructions_per_equation'] / 1e3:.1f}k instructions, "
                f"{part['last_level_read_misses_per_equation']:.1f} + "
                f"{part['last_level_write_misses_per_equation']:.1f} last-level misses")
    first = rows[0]
    for row in rows[1:]:
        row["growth_from_N"] = first["N"]
        for key in COUNTED_EVENTS.values():
            k = f"{key}_per_equation"
            row[f"{key}_growth"] = row[k] / first[k] if first[k] > 0 else None
    return {"caches": COUNTED_CACHES, "rows": rows}


def run_counted(quick: bool = False, passes: bool = False) -> dict:
    """Compile work per equation counted by cachegrind, N = 1000 and 10000 (issue 17)."""
    return {"benchmark": "scaling_counted",
            "compile_counted": compile_counted((1000,) if quick else (1000, 10000),
                                               passes=passes)}


def _exponents(rows: list[dict], key, same_grid: bool = False) -> list[dict]:
    """Growth exponents between successive rows; with ``same_grid``, only between rows
    that logged the same number of output points (None otherwise)."""
    out = []
    for a, b in zip(rows, rows[1:]):
        ta, tb = key(a), key(b)
        comparable = not same_grid or a["output_points"] == b["output_points"]
        out.append({"from_N": a["N"], "to_N": b["N"],
                    "exponent": growth_exponent(a["N"], ta, b["N"], tb)
                    if comparable else None})
    return out


def run(quick: bool = False, tiny: bool = False, large: bool = False) -> dict:
    """Compile-time and simulation scaling (RC ladder, mass-spring chain) and SciPy baseline."""
    sizes = [5, 10] if tiny else [n for n in SIZES if not (quick and n >= 10000)]
    alone = [10] if tiny else [1000] + ([] if quick else [10000]) + ([LARGE] if large else [])
    out = {"benchmark": "scaling",
           "settings": {"sizes": sizes, "t_stop_s": T_STOP, "rtol": RTOL, "atol": ATOL,
                        "solver": "cvodes", "output_points": N_OUT,
                        "output_points_N10000": N_OUT_LARGE,
                        "rc_ladder": {"R_ohm": R_SERIES, "C_F": C_SHUNT, "V": V_SOURCE},
                        "mass_spring_chain": {"m_kg": MASS, "k_N_m": SPRING,
                                              "b_N_s_m": DAMPER,
                                              "x_last_start_m": X_LAST}},
           "models": {}}
    for kind in MODELS:
        rows = []
        for n in sizes:
            gc.collect()
            row, final, grid = measure(kind, n, simulate_twice=n < (1000 if quick else 10000),
                                       compiles=1 if tiny else _compile_repeats(n, quick))
            if kind == "rc_ladder":
                base = scipy_rc_ladder(n, grid, repeats=3 if n <= 100 else 1)
                mech = row.get("simulate_second_s", row["simulate_first_s"])
                row["scipy_bdf_sparse"] = {
                    "time": base["time"], "success": base["success"], "nfev": base["nfev"],
                    "njev": base["njev"], "nlu": base["nlu"],
                    "ratio_scipy_over_mechatron_simulate": ratio(base["time"]["median_s"],
                                                                 mech),
                    "ratio_scipy_over_mechatron_integrate_variable":
                        ratio(base["time"]["median_s"],
                              row["simulate_profile_s"]["integrate_variable_s"]),
                    "ratio_scipy_over_mechatron_solver_call":
                        ratio(base["time"]["median_s"],
                              row["simulate_profile_s"]["solver_call_s"]),
                    "max_abs_diff_final_v": float(np.max(np.abs(final - base["final"]))),
                }
                log(f"rc_ladder N={n}: scipy BDF {base['time']['median_s']:.3f} s")
            rows.append(row)
        goals = {str(n): {"goal_s": GOALS[n], "compile_s": r["compile_s"],
                          "compile_cpu_s": r["compile_cpu_s"],
                          "met": r["compile_s"] < GOALS[n]}
                 for r in rows for n in [r["N"]] if n in GOALS}
        passes = sorted({k for r in rows for k in r["passes_s"] if k != "total"})
        out["models"][kind] = {
            "rows": rows,
            "compile_goals": goals,
            "growth_exponents": {
                "compile": _exponents(rows, lambda r: r["compile_s"]),
                "per_pass": {p: _exponents(rows, lambda r, p=p: r["passes_s"].get(p))
                             for p in passes},
                "simulate": _exponents(rows, lambda r: r.get("simulate_second_s",
                                                             r["simulate_first_s"]),
                                       same_grid=True),
                "integrate_variable": _exponents(
                    rows, lambda r: r["simulate_profile_s"]["integrate_variable_s"],
                    same_grid=True),
                "solver_call": _exponents(
                    rows, lambda r: r["simulate_profile_s"]["solver_call_s"]),
            },
        }
    out["compile_scaling"] = compile_scaling(alone, fresh=not tiny)
    out["notes"] = [
        "Timings are wall clock on a shared machine (see environment.load_average); "
        "compile_cpu_s is the process CPU time of the same compile, less sensitive to "
        "other load. compile_s is the median of compile_repeats fresh builds, and the "
        "row's other compile figures come from that run.",
        f"N = 10000 logs {N_OUT_LARGE} output points instead of {N_OUT}, so its simulate "
        "time is not comparable row to row. The largest size (N = 1000 with --quick) "
        "simulates once: simulate_first_s only, which includes building the integrator.",
        "simulate_* is mt.simulate on the compiled model (initialization, integration, "
        "evaluation of every logged variable at every output point). simulate_profile_s "
        "splits the profiled call (the second, or the only one): integrate_variable_s is "
        "the CVODES run plus the conversion of its state trajectory to NumPy; the other "
        "entries overlap it and each other (cumulative times).",
        "logging_by_buffer: the same logged values computed with casadi.Function.buffer "
        "into a NumPy array (no casadi.DM round trip), for comparison.",
        "rc_ladder ratio: SciPy time / Mechatron simulate time (second call when there is "
        "one); > 1 means Mechatron is faster.",
        "compile_scaling: the RC ladder compiled once per N, each in a fresh process; "
        "compile_cpu_s is the process CPU time of compile_model, passes_cpu_s "
        "its passes (passes_s: wall clock), peak_rss_MB the process's peak (instance built included); the goals are "
        "issue 17's, on CPU time. N = 100000 only with --large.",
    ]
    return out


def run_large(quick: bool = False) -> dict:
    """Compile-time and simulation scaling, and the RC ladder compiled at N = 100000."""
    return run(quick=quick, large=True)


if __name__ == "__main__":
    if "--compile-one" in sys.argv:      # one size in this process (compile_scaling)
        print(json.dumps(compile_once(int(sys.argv[sys.argv.index("--compile-one") + 1]))))
    elif "--arrays-one" in sys.argv:     # the array peer of one size (compile_growth)
        print(json.dumps(arrays_once(int(sys.argv[sys.argv.index("--arrays-one") + 1]))))
    elif "--counted-one" in sys.argv:    # one process of compile_counted
        at = sys.argv.index("--counted-one")
        counted_one(int(sys.argv[at + 1]), sys.argv[at + 2])
    elif "--counted" in sys.argv:
        sys.argv.remove("--counted")
        by_pass = "--passes" in sys.argv
        if by_pass:
            sys.argv.remove("--passes")

        def counted(quick: bool = False) -> dict:
            """Compile work per equation counted by cachegrind (issue 17)."""
            return run_counted(quick, by_pass)
        main(counted)
    elif "--growth" in sys.argv:
        at = sys.argv.index("--growth")
        rounds = int(sys.argv.pop(at + 1)) if sys.argv[at + 1:at + 2] and \
            sys.argv[at + 1].isdigit() else 4
        sys.argv.pop(at)

        def growth(quick: bool = False) -> dict:
            """Growth of the compile time per equation, N = 1000 to 100000 (issue 17)."""
            return run_growth(quick, rounds)
        main(growth)
    elif "--large" in sys.argv:
        sys.argv.remove("--large")
        main(run_large)
    else:
        main(run)

"""The library walk: every concrete component class of ``mechatron.library`` (found by the
catalog, so classes added later are checked too) must

1. be locally balanced (:func:`mechatron.core.balance.check_balance`, Modelica's rule:
   equations = unknowns - through variables of its own connectors - inputs);
2. state its equations in its docstring: the class's own docstring must hold a relation in
   code markup, i.e. a ````code```` or ```code``` span containing ``=`` (``==`` counts),
   or a literal block (a paragraph ending in ``::`` followed by indented lines) with a
   line containing ``=``;
3. give every Parameter, Variable, Input and Output (its own and those of its ports'
   connectors) a unit and a one-line doc.

Each check names every offending class in one failure message. Classes that fail for a
reason their owner is chasing are listed in :data:`KNOWN_EXCEPTIONS` with the reason; an
entry that no longer fails raises a warning (not a failure, so that its owner's fix does
not break the suite), asking for its removal.
"""

import re
import warnings

import pytest

from mechatron.core import Connector, Parameter, Variable
from mechatron.core.balance import BalanceReport, check_balance
from mechatron.library import catalog

#: "module.Class" -> reason. Only for classes owned by others; each is reported to the
#: lead engineer.
KNOWN_EXCEPTIONS: dict[str, str] = {}

COMPONENTS = catalog.components()
IMPORT_ERRORS = catalog.import_errors()

_SPAN = re.compile(r"``(.+?)``|`([^`]+?)`", re.S)


def states_equations(doc: str | None) -> bool:
    """True if ``doc`` holds a relation in code markup (the documented rule above)."""
    if not doc:
        return False
    for m in _SPAN.finditer(doc):
        if "=" in (m.group(1) or m.group(2) or ""):
            return True
    lines = doc.splitlines()
    for k, line in enumerate(lines):
        if line.rstrip().endswith("::"):
            indent = len(line) - len(line.lstrip())
            for follow in lines[k + 1:]:
                if not follow.strip():
                    continue
                if len(follow) - len(follow.lstrip()) <= indent:
                    break
                if "=" in follow:
                    return True
    return False


def declaration_problems(cls) -> list[str]:
    problems = []
    owners = [(cls.__name__, cls)] + [
        (f"{cls.__name__}.{k}", type(t)) for k, t in cls._templates.items()
        if isinstance(t, Connector)]
    for where, klass in owners:
        for key, decl in klass._declarations.items():
            if not isinstance(decl, (Parameter, Variable)):
                continue
            if not str(decl.unit).strip():
                problems.append(f"{where}.{key}: no unit")
            if not str(decl.doc).strip():
                problems.append(f"{where}.{key}: no doc")
    return problems


def failures(check) -> dict[str, str]:
    out = {}
    for info in COMPONENTS:
        msg = check(info)
        if msg:
            out[info.qualname] = msg
    return out


def assert_none_except_known(found: dict[str, str], what: str) -> None:
    unexpected = {k: v for k, v in found.items() if k not in KNOWN_EXCEPTIONS}
    if unexpected:
        lines = "\n  ".join(f"{k}: {v}" for k, v in sorted(unexpected.items()))
        pytest.fail(f"{len(unexpected)} component class(es) {what}:\n  {lines}",
                    pytrace=False)


def test_the_walk_finds_the_library():
    assert not IMPORT_ERRORS, f"library modules fail to import: {IMPORT_ERRORS}"
    sections = {c.section for c in COMPONENTS}
    assert {"electrical", "rotational", "translational", "mechanisms"} <= sections
    assert len(COMPONENTS) >= 50


def test_every_component_is_locally_balanced():
    def check(info):
        report = check_balance(info.cls)
        return "" if report.balanced else report.summary()
    assert_none_except_known(failures(check), "are not locally balanced")


def test_every_docstring_states_the_equations():
    def check(info):
        doc = info.cls.__dict__.get("__doc__")
        return "" if states_equations(doc) else \
            "the docstring states no equation (no `...=...` in code markup)"
    assert_none_except_known(failures(check), "do not state their equations")


def test_every_declaration_has_a_unit_and_a_doc():
    def check(info):
        return "; ".join(declaration_problems(info.cls))
    assert_none_except_known(failures(check), "have undocumented declarations")


def test_known_exceptions_still_fail():
    """An entry of KNOWN_EXCEPTIONS whose class now passes every check should be removed
    (a warning)."""
    by_name = {c.qualname: c for c in COMPONENTS}
    stale = []
    for name in KNOWN_EXCEPTIONS:
        info = by_name.get(name)
        if info is None:
            stale.append(f"{name} (no such component)")
            continue
        ok = (check_balance(info.cls).balanced
              and states_equations(info.cls.__dict__.get("__doc__"))
              and not declaration_problems(info.cls))
        if ok:
            stale.append(name)
    if stale:
        warnings.warn(f"remove from KNOWN_EXCEPTIONS, they pass now: {stale}", stacklevel=1)


# ------------------------------------------------------------------ the rule's own tests
def test_docstring_rule_accepts_spans_and_literal_blocks_only():
    assert states_equations("Resistor: ``v = R i``.")
    assert states_equations("Relay: `y == u`.")
    assert states_equations("Friction::\n\n    f = F_C tanh(v/v_C)\n\nMore text.")
    assert not states_equations("A resistor obeys Ohm's law.")
    assert not states_equations("Uses `R` and `L` only.")
    assert not states_equations("Example::\n\n    no relation here\nv = R i outside\n")
    assert not states_equations(None)


def test_balance_rule_counts_a_missing_and_an_extra_equation():
    import mechatron as mt
    from mechatron.library import rotational as rot

    class Missing(rot.TwoFlange):
        """``tau = ?`` (one equation short on purpose)."""

    class Extra(rot.TwoFlange):
        """``tau = 0`` and ``w = 0`` (one equation too many)."""

        def equations(self):
            return [self.tau == 0, self.w == 0]

    class Composite(mt.Component):
        """Spring in series with a damper between the composite's flanges ``A``, ``B``:
        ``tau = k phi_s = D w_d``."""

        A = rot.Flange(doc="Flange A")
        B = rot.Flange(doc="Flange B")
        spring = rot.RotationalSpring(k=10.0)
        damper = rot.RotationalDamper(D=1.0)

        def equations(self):
            return [mt.connect(self.A, self.spring.A),
                    mt.connect(self.spring.B, self.damper.A),
                    mt.connect(self.damper.B, self.B)]

    missing, extra, comp = (check_balance(c) for c in (Missing, Extra, Composite))
    assert isinstance(missing, BalanceReport)
    assert (missing.equations, missing.required) == (3, 4) and not missing.balanced
    assert "1 equation(s) missing" in missing.summary()
    assert (extra.equations, extra.required) == (5, 4) and "too many" in extra.summary()
    # 2 own ports (4) + spring (7) + damper (6) = 17 unknowns, 2 top-level through;
    # equations: spring 5 + damper 4 + three 2-port sets of 2 each = 15
    assert (comp.unknowns, comp.top_through, comp.equations) == (17, 2, 15)
    assert comp.balanced


def test_check_balance_rejects_what_is_not_a_component():
    with pytest.raises(TypeError, match="expected a Component"):
        check_balance(int)
    with pytest.raises(TypeError, match="expected a Component"):
        check_balance(3.0)


def test_balance_rule_counts_discrete_states_of_event_actions():
    """A variable assigned by ``sample``/``when`` and never differentiated is a discrete
    state (the compiler adds ``der(v) == 0``): one equation each; re-initializing a
    continuous state adds none."""
    import mechatron as mt
    from mechatron.core.events import Clock, sample, when

    class Hold(mt.Component):
        """Sample and hold: ``y = u`` at each tick, held between ticks."""

        u = mt.Input("1", doc="Input")
        y = mt.Output("1", doc="Held output")
        x = mt.Variable("1", doc="Memory")

        def equations(self):
            return [sample(Clock(0.1), output={self.y: self.u}, update={self.x: self.u})]

    class Bouncing(mt.Component):
        """Ball: ``dh/dt = v``, ``dv/dt = -g``, ``v := -e v`` at impact."""

        h = mt.Variable("m", start=1.0, doc="Height")
        v = mt.Variable("m/s", doc="Velocity")

        def equations(self):
            return [mt.der(self.h) == self.v, mt.der(self.v) == -9.81,
                    when(self.h < 0, update={self.v: -0.8 * self.v})]

    hold, ball = check_balance(Hold), check_balance(Bouncing)
    assert (hold.equations, hold.required) == (2, 2) and hold.balanced
    assert (ball.equations, ball.required) == (2, 2) and ball.balanced

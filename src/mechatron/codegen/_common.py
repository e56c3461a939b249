"""Helpers shared by the C and FMU generators: errors, templates, C identifiers."""

from __future__ import annotations

import keyword
import math
import re
from importlib import resources

from mechatron.errors import MechatronError

__all__ = ["CodegenError", "render", "c_identifier", "unique_identifiers", "c_string",
           "c_double", "c_array"]

_PLACEHOLDER = re.compile(r"@\{(\w+)\}")


class CodegenError(MechatronError, RuntimeError):
    """Code generation, compilation or an FMU export failed (a missing compiler, a model
    that the target cannot express, a compiler error)."""


def render(template: str, **values) -> str:
    """The template file ``templates/<template>`` with each ``@{key}`` replaced.

    ``@{...}`` is used (not ``$``) so that Makefiles and C keep their own syntax. A key the
    template uses but ``values`` lacks is an error, so that no placeholder survives.
    """
    text = resources.files("mechatron.codegen").joinpath("templates/" + template).read_text()
    missing = sorted({k for k in _PLACEHOLDER.findall(text) if k not in values})
    if missing:
        raise CodegenError(f"template {template}: no value for {', '.join(missing)} "
                           "(a bug in Mechatron's code generator).")
    return _PLACEHOLDER.sub(lambda m: str(values[m.group(1)]), text)


def c_identifier(text: str) -> str:
    """``text`` as a C identifier: every other character becomes ``_``."""
    ident = re.sub(r"\W", "_", text, flags=re.ASCII).strip("_") or "x"
    ident = re.sub(r"_+", "_", ident)
    if ident[0].isdigit() or keyword.iskeyword(ident):
        ident = "m_" + ident
    return ident


def unique_identifiers(names, taken: set[str] | None = None) -> list[str]:
    """C identifiers for ``names``, made unique (``_2``, ``_3``... on a clash);
    ``taken`` is updated with the identifiers used."""
    taken = set() if taken is None else taken
    out = []
    for name in names:
        base = c_identifier(name)
        ident, k = base, 2
        while ident in taken:
            ident, k = f"{base}_{k}", k + 1
        taken.add(ident)
        out.append(ident)
    return out


def c_string(text: str) -> str:
    """A C string literal of ``text`` (ASCII; other characters as octal escapes)."""
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ch == "\n":
            out.append("\\n")
        elif 32 <= ord(ch) < 127:
            out.append(ch)
        else:
            out.extend(f"\\{b:03o}" for b in ch.encode("utf-8"))
    return '"' + "".join(out) + '"'


def c_double(x: float) -> str:
    """A C99 double literal that reads back as exactly ``x``."""
    x = float(x)
    if math.isnan(x):
        raise CodegenError("cannot write NaN as a constant of the generated code.")
    if math.isinf(x):
        return "HUGE_VAL" if x > 0 else "(-HUGE_VAL)"
    text = repr(x)
    return text if any(c in text for c in ".en") else text + ".0"


def c_array(items) -> str:
    """The elements of a C initializer (``0`` for an empty array)."""
    items = list(items)
    return ", ".join(items) if items else "0"

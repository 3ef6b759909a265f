"""The one validation layer at every way in: numbers, and (from :mod:`bimkit.documents`) text, YAML
and JSON documents read within the limits of :mod:`bimkit.limits`. Output paths: :mod:`bimkit.outputs`.

Every check raises :class:`bimkit.errors.InputError` with a message that names the option, the
file and line or the YAML path, and what is wrong (``fine_tuning.particles: 1000000000000 is above
the maximum 200000``); the CLIs print it as one line on stderr and exit with code 2, before any
work starts. The ranges of the config files live in their JSON Schemas (``bimkit/schemas``);
the ranges of command-line options are given where each option is declared
(:func:`bimkit.cli.number_option`).
"""

from __future__ import annotations

import math

from bimkit.documents import (
    check_finite_tree,
    open_input,
    parse_json,
    parse_yaml,
    read_bytes,
    read_json,
    read_text,
    read_yaml,
)
from bimkit.errors import InputError

__all__ = [
    "check_finite_tree",
    "check_number",
    "open_input",
    "parse_json",
    "parse_yaml",
    "range_problem",
    "read_bytes",
    "read_json",
    "read_text",
    "read_yaml",
    "show_number",
]


def show_number(value: float) -> str:
    """A number as the user would write it: ``1000000000000``, ``1e-09``, ``nan``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e16:
        return str(int(value))
    return repr(value)


def range_problem(
    value: float,
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    above: float | None = None,
    below: float | None = None,
) -> str | None:
    """What is wrong with ``value`` (None when it is finite and within the bounds).

    ``minimum``/``maximum`` are inclusive, ``above``/``below`` exclusive (JSON Schema's
    ``exclusiveMinimum``/``exclusiveMaximum``).
    """
    shown = show_number(value)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return f"expected a number, got {value!r}"
    if isinstance(value, float) and not math.isfinite(value):
        return f"{shown} is not a finite number"
    if minimum is not None and value < minimum:
        return f"{shown} is below the minimum {show_number(minimum)}"
    if above is not None and value <= above:
        return f"{shown} must be > {show_number(above)}"
    if maximum is not None and value > maximum:
        return f"{shown} is above the maximum {show_number(maximum)}"
    if below is not None and value >= below:
        return f"{shown} must be < {show_number(below)}"
    return None


def check_number(
    value: float,
    name: str,
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    above: float | None = None,
    below: float | None = None,
) -> float:
    """``value`` when finite and within the bounds, else :class:`InputError` naming ``name``."""
    problem = range_problem(value, minimum=minimum, maximum=maximum, above=above, below=below)
    if problem is not None:
        raise InputError(f"{name}: {problem}")
    return value

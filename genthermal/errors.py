"""Errors raised for bad user input.

Every error that reaches a user names the offending field and value; the CLI prints the message
(no traceback) and exits with a non-zero code.
"""

import reprlib

#: Longest ``repr`` of a bad value an error message shows, characters.
SHOWN_VALUE_CHARS = 120


class GenthermalError(Exception):
    """Base class of every error genthermal raises on purpose."""


class InputError(GenthermalError, ValueError):
    """Bad user input: a scenario, data file, parameter or argument that cannot be used.

    Parameters
    ----------
    field : str
        Where the bad value sits (``"actions[2].duration_min"``, ``"column T_iron, row 17"``).
    value : object
        The offending value, shown with ``repr`` (a long one cut to its first
        :data:`SHOWN_VALUE_CHARS` characters: a whole file read as a value must not flood the terminal).
    reason : str
        What is wrong and, where it helps, what would be accepted.
    """

    def __init__(self, field: str, value, reason: str):
        self.field = field
        self.value = value
        self.reason = reason
        super().__init__(f"{field} = {shown_value(value)}: {reason}")

    def __reduce__(self):
        # rebuilt from its three fields (an error raised in a worker process comes back as itself)
        return type(self), (self.field, self.value, self.reason)


def shown_value(value) -> str:
    """``repr(value)`` cut to :data:`SHOWN_VALUE_CHARS` characters, built without rendering more.

    A text keeps its length in the message; a container is rendered a few items and levels deep
    (:mod:`reprlib`), so a YAML alias bomb (a list of lists shared a thousand times) or a huge
    number costs no more than its first characters.
    """
    if isinstance(value, str):
        if len(value) <= SHOWN_VALUE_CHARS:
            return repr(value)
        return f"{repr(value[:SHOWN_VALUE_CHARS])[:SHOWN_VALUE_CHARS]}... ({len(value)} characters)"
    shown = _SHORT.repr(value)
    return shown if len(shown) <= SHOWN_VALUE_CHARS else f"{shown[:SHOWN_VALUE_CHARS]}..."


class _ShortRepr(reprlib.Repr):
    def repr_int(self, value, level):
        if value.bit_length() > 256:  # rendering 10**5000 raises, 10**400 floods the line
            return f"<an integer of {int(value.bit_length() * 0.30103) + 1} digits>"
        return super().repr_int(value, level)


_SHORT = _ShortRepr()
_SHORT.maxlevel, _SHORT.maxlist, _SHORT.maxtuple, _SHORT.maxdict = 3, 8, 8, 8
_SHORT.maxset, _SHORT.maxfrozenset, _SHORT.maxdeque, _SHORT.maxarray = 8, 8, 8, 8
_SHORT.maxstring, _SHORT.maxother, _SHORT.maxlong = SHOWN_VALUE_CHARS, SHOWN_VALUE_CHARS, SHOWN_VALUE_CHARS


class ParameterError(InputError):
    """A parameter value that is not physical (negative conductance, zero capacitance, ...)."""


class CompilerNotFoundError(GenthermalError, RuntimeError):
    """No C compiler is available; the interpreted CasADi path still works."""

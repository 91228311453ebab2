"""Errors raised for bad user input.

Every error that reaches a user names the offending field and value; the CLI prints the message
(no traceback) and exits with a non-zero code.
"""


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
        shown = repr(value)
        if len(shown) > SHOWN_VALUE_CHARS:
            shown = f"{shown[:SHOWN_VALUE_CHARS]}... ({len(shown)} characters)"
        super().__init__(f"{field} = {shown}: {reason}")


class ParameterError(InputError):
    """A parameter value that is not physical (negative conductance, zero capacitance, ...)."""


class CompilerNotFoundError(GenthermalError, RuntimeError):
    """No C compiler is available; the interpreted CasADi path still works."""

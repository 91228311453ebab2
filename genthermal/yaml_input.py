"""Reading the YAML a user writes (scenarios, model files) without silent surprises.

``yaml.safe_load`` keeps the last of two equal keys without a word (``h_end_air`` given twice: the
second wins) and overflows Python's stack on deeply nested brackets. :func:`load_user_yaml`
refuses both with an :class:`~genthermal.errors.InputError`; YAML syntax errors stay
``yaml.YAMLError`` for the caller to explain with its line.
"""

from __future__ import annotations

import yaml

from .errors import InputError


class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that refuses a mapping with the same key twice."""

    def construct_mapping(self, node, deep=False):
        first_line: dict = {}
        for key_node, _ in node.value:
            key, line = self.construct_object(key_node, deep=True), key_node.start_mark.line + 1
            try:
                if key in first_line:
                    raise InputError(f"key {key!r}", f"line {line}", f"given twice (first at line "
                                     f"{first_line[key]}); YAML would silently keep the last: remove one")
                first_line[key] = line
            except TypeError:  # an unhashable key: SafeLoader's own error explains it
                break
        return super().construct_mapping(node, deep)


def load_user_yaml(text: str, source: str):
    """Parse ``text`` (from ``source``, named in errors) as YAML with unique keys.

    Raises
    ------
    InputError
        A key given twice in one mapping, or brackets nested too deeply to read.
    yaml.YAMLError
        A syntax error (the caller names the line).
    """
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
    except RecursionError:
        raise InputError(source, "nesting", "brackets or indentation nested too deeply to be a "
                         "scenario or model file") from None

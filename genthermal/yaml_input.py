"""Reading the YAML a user writes (scenarios, model files) without silent surprises.

``yaml.safe_load`` keeps the last of two equal keys without a word (``h_end_air`` given twice: the
second wins), overflows Python's stack on deeply nested brackets, and reads an integer of 5000
digits into one no message can show and no float can hold. :func:`load_user_yaml` refuses all
three with an :class:`~genthermal.errors.InputError`; YAML syntax errors stay ``yaml.YAMLError``
for the caller to explain with its line. :func:`read_user_text` reads the file with a size limit.
"""

from __future__ import annotations

import os

import yaml

from .errors import InputError
from .input_limits import MAX_YAML_BYTES, read_bounded

#: Most digits a YAML integer may have: more than a float holds (1.8e308) is not a physical value.
MAX_INTEGER_DIGITS = 308


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

    def construct_yaml_int(self, node):
        digits = sum(character.isalnum() for character in str(node.value))
        if digits > MAX_INTEGER_DIGITS:
            raise InputError(f"line {node.start_mark.line + 1}", f"an integer of {digits} digits",
                             f"more than {MAX_INTEGER_DIGITS} digits: no physical value is that large")
        return super().construct_yaml_int(node)


_UniqueKeyLoader.add_constructor("tag:yaml.org,2002:int", _UniqueKeyLoader.construct_yaml_int)


def read_user_text(path: str | os.PathLike, what: str) -> str:
    """The UTF-8 text of a scenario or model file, at most :data:`MAX_YAML_BYTES` bytes.

    Raises
    ------
    InputError
        A device, a folder or too large a file (:func:`genthermal.input_limits.read_bounded`).
    UnicodeDecodeError
        Not UTF-8 text (the caller names the file).
    """
    return read_bounded(path, what, MAX_YAML_BYTES).decode("utf-8")


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

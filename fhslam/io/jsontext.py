"""JSON text for the package's JSON files (maps, keyframe graphs), read so that every
number that JSON has not can be refused naming its field and its line.

Python's :func:`json.loads` reads more than JSON: the words ``NaN``, ``Infinity`` and
``-Infinity``, and a number too large for a float (``1e400``) as ``inf``; an integer of more
than 4300 digits raises a bare :class:`ValueError`, and brackets nested some thousand deep a
:class:`RecursionError`. :func:`parse_json` reads each of the first as a :class:`NonFinite`, a
float (NaN or infinite) that remembers how it was written and on which text line, so that a
reader's check for finite numbers names the field and the line (``"m.json: lines[1]: 'n'
... got NaN (line 3)"``); it refuses the others, naming the file and the line.
"""

from __future__ import annotations

import json
import math
import re
from os import PathLike
from typing import Any

from fhslam.errors import InputError

__all__ = ["MAX_INTEGER_DIGITS", "NonFinite", "parse_json"]

MAX_INTEGER_DIGITS = 100
"""Longest integer read, in digits (far past any count or index a file holds)."""

_TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|(-?(?:Infinity|NaN|\d+(?:\.\d+)?(?:[eE][+-]?\d+)?))')
"""A JSON string (skipped), or a number or one of Python's extra words (group 1)."""


class NonFinite(float):
    """A number of a JSON file that is no finite float: ``NaN``, ``Infinity``, ``-Infinity``
    or beyond the largest float (``1e400``). Its value is NaN or ±inf; its ``repr`` is the
    text as written and the text line, ``"NaN (line 3)"``."""

    text: str
    line: int

    def __new__(cls, text: str) -> NonFinite:
        self = super().__new__(cls, float(text))
        self.text, self.line = text, 0
        return self

    def __repr__(self) -> str:
        return f"{self.text} (line {self.line})"

    __str__ = __repr__


class _Refused(Exception):
    def __init__(self, token: str, why: str) -> None:
        super().__init__(why)
        self.token, self.why = token, why


def _int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_INTEGER_DIGITS:
        raise _Refused(
            text, f"an integer of {len(text.lstrip('-'))} digits (at most {MAX_INTEGER_DIGITS})"
        )
    return int(text)


def _not_finite(token: str) -> bool:
    return token.lstrip("-") in ("NaN", "Infinity") or (
        any(c in token for c in ".eE") and not math.isfinite(float(token))
    )


def _lines(text: str, token: str | None = None) -> list[int]:
    """The text lines (from 1) of the tokens outside strings that are no finite number, in
    order; or, given ``token``, of the first one written so."""
    out = []
    for m in _TOKEN.finditer(text):
        t = m.group(1)
        if t is not None and (t == token if token is not None else _not_finite(t)):
            out.append(text.count("\n", 0, m.start()) + 1)
            if token is not None:
                break
    return out


def parse_json(text: str, path: str | PathLike[str], error: type[InputError]) -> Any:
    """The JSON value of ``text``, read from the file ``path``; ``NaN``, ``Infinity``,
    ``-Infinity`` and numbers beyond the largest float as :class:`NonFinite` (for the reader
    to refuse, naming its field).

    Raises
    ------
    InputError
        Of type ``error``, ``"{path}:{line}: ..."``: not valid JSON, or an integer of more
        than :data:`MAX_INTEGER_DIGITS` digits; ``"{path}: ..."``: nested too deeply.
    """
    found: list[NonFinite] = []

    def number(token: str) -> float:
        value = float(token)
        if math.isfinite(value):
            return value
        found.append(NonFinite(token))
        return found[-1]

    def word(token: str) -> float:
        found.append(NonFinite(token))
        return found[-1]

    try:
        data = json.loads(text, parse_constant=word, parse_float=number, parse_int=_int)
    except json.JSONDecodeError as e:
        raise error(f"{path}:{e.lineno}: not valid JSON ({e.msg})") from None
    except _Refused as e:
        raise error(f"{path}:{_lines(text, e.token)[0]}: {e.why}") from None
    except RecursionError:
        raise error(f"{path}: not readable JSON (lists or objects nested too deeply)") from None
    if found:  # the parser met them in the order of the text
        for value, line in zip(found, _lines(text), strict=False):
            value.line = line
    return data

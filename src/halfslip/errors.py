"""The input error of halfslip and the small checks that raise it.

Every bad input (scene file, load table, profile table, sweep file) ends in a
:class:`HalfslipInputError` whose one-line text names the file, the line and
the field path, e.g. ``scene.yaml:14: loads[1].cycles.Q.amplitude: ...``.

The ``check_*`` helpers validate one plain Python value (as parsed from YAML
or passed by a caller) and raise the error with the field path filled in; the
scene reader adds the file and the line afterwards (:meth:`located`).
"""
from __future__ import annotations

import difflib
import math
import re
from collections.abc import Collection, Mapping
from numbers import Real
from typing import Any

EXCERPT_CHARS = 40
"""Most characters of input text an error message quotes (:func:`excerpt`): enough to
recognise a value or a key, too few to echo a file that was read by mistake."""

_FIELD_CHARS = 80  # the longest field path of a valid scene is about 40 characters
_MESSAGE_CHARS = 600  # the longest message composed by halfslip is about 300 characters

_NUMBER_WITH_UNIT = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*[^\d\s.eE+-]")


class HalfslipInputError(ValueError):
    """A bad input, located as precisely as known.

    Parameters
    ----------
    message : str
        What is wrong and, where possible, how to fix it.
    file : str, optional
        The file the input came from.
    line : int, optional
        1-based line in `file`.
    field : str, optional
        Path of the offending field, e.g. ``loads[1].cycles.Q.amplitude``.

    Notes
    -----
    ``str(error)`` is one line, ``"{file}:{line}: {field}: {message}"``, with
    the parts that are None left out.
    """

    def __init__(
        self,
        message: str,
        *,
        file: str | None = None,
        line: int | None = None,
        field: str | None = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.file = file
        self.line = line
        self.field = field

    def __str__(self) -> str:
        location = ":".join(str(part) for part in (self.file, self.line) if part is not None)
        field = self.field
        if field and len(field) > _FIELD_CHARS:  # a field path holds keys from the input: keep it short
            field = f"{field[:_FIELD_CHARS]}..."
        message = self.message
        if len(message) > _MESSAGE_CHARS:  # backstop; quotes are cut to EXCERPT_CHARS by excerpt()
            message = f"{message[:_MESSAGE_CHARS]}..."
        parts = [part for part in (location, field, message) if part]
        # one line whatever the input: control characters from keys or values are escaped
        return "".join(c if c.isprintable() else repr(c)[1:-1] for c in ": ".join(parts))

    def located(self, file: str | None, line: int | None) -> HalfslipInputError:
        """Return a copy with `file` and `line` filled in where still unknown."""
        return HalfslipInputError(
            self.message,
            file=self.file if self.file is not None else file,
            line=self.line if self.line is not None else line,
            field=self.field,
        )


def excerpt(text: Any, limit: int = EXCERPT_CHARS) -> str:
    """Quote input text for an error message: ``repr`` of at most `limit` characters.

    Every message that quotes text from an input file goes through here, so a
    file read by mistake (``halfslip validate /etc/passwd``) is never echoed:
    longer text is cut and marked with ``...`` and the number of characters
    left out. Control characters come out escaped (``repr``), so the quote is
    one printable line.
    """
    text = str(text)
    if len(text) <= limit:
        return repr(text)
    return f"{text[:limit]!r}... ({len(text) - limit:,} more characters)"


def describe(value: Any) -> str:
    """Name the type of a parsed value the way a scene author would."""
    if value is None:
        return "nothing (null)"
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"the string {excerpt(value)}"
    if isinstance(value, Mapping):
        return "a mapping"
    if isinstance(value, (list, tuple)):
        return "a list"
    if isinstance(value, Real):
        return f"the number {_number_text(value)}"
    return f"a value of type {type(value).__name__}"


def _number_text(value: Real) -> str:
    """``repr`` of a number, shortened for integers too long to print whole."""
    if isinstance(value, int) and value.bit_length() > 1100:  # about 330 digits: beyond any float
        return f"(an integer of about {int(value.bit_length() * 0.30103) + 1:,} digits)"
    return repr(value)


def check_number(
    value: Any,
    field: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
) -> float:
    """Return `value` as a finite float, or raise.

    Parameters
    ----------
    value : Any
        The parsed value.
    field : str
        Field path for the error.
    positive, nonnegative : bool
        Also require ``value > 0`` (``>= 0``).

    Returns
    -------
    float

    Raises
    ------
    HalfslipInputError
        For booleans, strings (with a hint when the string carries a unit or
        is a quoted number), other types, NaN, infinities and sign violations.
    """
    if isinstance(value, str):
        if _NUMBER_WITH_UNIT.match(value):
            raise HalfslipInputError(
                f"{excerpt(value)} carries a unit; give the number in SI units without a unit",
                field=field,
            )
        try:
            float(value)
        except ValueError:
            raise HalfslipInputError(f"expected a number, got {describe(value)}", field=field) from None
        raise HalfslipInputError(
            f"expected a number, got {describe(value)}; write the number without quotes", field=field
        )
    if isinstance(value, bool) or not isinstance(value, Real):
        raise HalfslipInputError(f"expected a number, got {describe(value)}", field=field)
    try:
        number = float(value)
    except OverflowError:  # an integer beyond the float range
        raise HalfslipInputError(f"is out of range: {describe(value)}; the largest number is 1.8e308",
                                 field=field) from None
    if not math.isfinite(number):
        raise HalfslipInputError(f"must be a finite number, got {number}", field=field)
    if positive and not number > 0:
        raise HalfslipInputError(f"must be > 0, got {number:g}", field=field)
    if nonnegative and not number >= 0:
        raise HalfslipInputError(f"must be >= 0, got {number:g}", field=field)
    return number


def check_count(value: Any, field: str, *, minimum: int = 1) -> int:
    """Return `value` as an int ``>= minimum``, or raise.

    Integral floats (``100.0``, ``1e2``) are accepted.
    """
    number = check_number(value, field)
    if not number.is_integer() or number < minimum:
        raise HalfslipInputError(f"must be an integer >= {minimum}, got {number:g}", field=field)
    return int(number)


def check_bool(value: Any, field: str) -> bool:
    """Return `value` if it is a boolean, or raise."""
    if not isinstance(value, bool):
        raise HalfslipInputError(f"expected true or false, got {describe(value)}", field=field)
    return value


def check_string(value: Any, field: str) -> str:
    """Return `value` if it is a non-empty string, or raise."""
    if not isinstance(value, str) or not value:
        raise HalfslipInputError(f"expected a text, got {describe(value)}", field=field)
    return value


def check_list(value: Any, field: str) -> list:
    """Return `value` as a list if it is a list or tuple, or raise."""
    if not isinstance(value, (list, tuple)):
        raise HalfslipInputError(f"expected a list, got {describe(value)}", field=field)
    return list(value)


def check_choice(value: Any, field: str, choices: Collection[str]) -> str:
    """Return `value` if it is one of `choices`, or raise with a suggestion."""
    if not isinstance(value, str) or value not in choices:
        raise HalfslipInputError(
            f"expected one of {', '.join(choices)}, got {describe(value)}{suggest(value, choices)}",
            field=field,
        )
    return value


def check_mapping(
    value: Any,
    field: str,
    allowed: Collection[str],
    required: Collection[str] = (),
) -> Mapping[str, Any]:
    """Check that `value` is a mapping with known keys and all required ones.

    Parameters
    ----------
    value : Any
        The parsed value.
    field : str
        Field path of the mapping ("" for the top level).
    allowed : collection of str
        Every key the mapping may have (including the required ones).
    required : collection of str
        Keys that must be present.

    Returns
    -------
    Mapping[str, Any]
        `value` itself.

    Raises
    ------
    HalfslipInputError
        For a non-mapping, an unknown key (with the closest valid key as
        hint) or a missing key; the field names the offending key.
    """
    if not isinstance(value, Mapping):
        raise HalfslipInputError(f"expected a mapping, got {describe(value)}", field=field or None)
    for key in value:
        if key not in allowed:
            raise HalfslipInputError(
                f"unknown key {excerpt(key)}{suggest(key, allowed)}", field=join(field, str(key))
            )
    for key in required:
        if key not in value:
            raise HalfslipInputError("missing required field", field=join(field, key))
    return value


def suggest(word: Any, choices: Collection[str]) -> str:
    """Return ``"; did you mean 'x'?"`` for the closest of `choices`, else ``""``."""
    if not isinstance(word, str):
        return ""
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    if not close:
        close = [choice for choice in choices if choice.lower() == word.lower()]
    return f"; did you mean {close[0]!r}?" if close else ""


def join(field: str, key: str) -> str:
    """Append `key` to the field path `field` (which may be empty)."""
    return f"{field}.{key}" if field else key

"""``key=value`` settings from the command line (a disturbance's knobs, a sensor's noise
figures), read into numbers with one-line errors that name the bad item."""

from __future__ import annotations

from collections.abc import Iterable


def parse_key_values(items: Iterable[str], allowed: Iterable[str], what: str,
                     error: type[Exception], integers: Iterable[str] = (),
                     choices: dict[str, tuple[str, ...]] | None = None) -> dict:
    """``{key: number}`` from ``key=value`` items; keys in ``integers`` are ints, keys in
    ``choices`` one of their words, the rest floats. A missing ``=``, a key not in
    ``allowed``, a key given twice or a value that is not a number (or not one of the
    key's words) raises ``error`` naming ``what`` (for example ``"current"``)."""
    allowed, integers, choices = list(allowed), set(integers), choices or {}
    values = {}
    for item in items:
        key, eq, text = item.partition("=")
        if not eq or key not in allowed:
            raise error(f"bad parameter {item!r} for {what}: use key=value with key in "
                        f"{', '.join(allowed)}")
        if key in values:
            raise error(f"{what}.{key} is given twice ({item!r}): give each key once")
        if key in choices:
            if text not in choices[key]:
                raise error(f"bad value {text!r} for {what}.{key}: choose one of "
                            f"{', '.join(choices[key])}")
            values[key] = text
            continue
        try:
            values[key] = int(text) if key in integers else float(text)
        except ValueError:
            raise error(f"bad value {text!r} for {what}.{key}: not a number") from None
    return values


def settings_of(kind: type, items: Iterable[str], flag: str, error: type[Exception],
                integers: Iterable[str] = ()):
    """``kind(**values)`` from ``key=value`` items, the keys ``kind``'s dataclass fields.
    A bad item, or a value ``kind`` refuses, raises ``error`` naming ``flag``."""
    from dataclasses import fields

    values = parse_key_values(items, [f.name for f in fields(kind)], flag, error, integers)
    try:
        return kind(**values)
    except error as e:
        raise error(f"{flag}: {e}") from None

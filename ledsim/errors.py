"""One error base for everything a user can get wrong.

:class:`LedsimError` means "the request cannot be carried out as asked" (a bad number, a
missing scene, a checkpoint for another link). The CLI catches it in one place and prints
one line with exit code 2; library users catch it (or :class:`ValueError`, which it also
is) the same way. Each part of the package raises its own subclass so a message can say
where it came from.
"""

import math


class LedsimError(ValueError):
    """Bad user input or an unusable file, reported by the CLI as one line, exit code 2."""


#: What ``str.splitlines`` breaks a line at: a user's text may bring any of them into a
#: message (``--link $'a\rb'``).
LINE_BREAKS = "\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"
_ESCAPED = {ord(c): repr(c)[1:-1] for c in LINE_BREAKS}


def one_line(message: str) -> str:
    """``message`` as one line: the line breaks in it shown escaped (``\\n``)."""
    return message.translate(_ESCAPED)


def check_ranges(checks, error: type[LedsimError] = LedsimError, joiner: str = " ") -> None:
    """Raise ``error`` for the first of ``checks`` that fails: each is ``(name, value,
    ok, allowed)``, failing when ``ok`` is false or ``value`` is not finite, with the
    message "NAME VALUE is not allowed: must be ALLOWED" (``joiner`` between the name and
    the value: ``" "`` for a flag, ``"="`` for a field)."""
    for name, value, ok, allowed in checks:
        if not (ok and math.isfinite(value)):
            raise error(f"{name}{joiner}{value!r} is not allowed: must be {allowed}")


#: Former name, kept so older scripts keep working.
UserError = LedsimError


def named(registry: dict, name: str, kind: str):
    """``registry[name]``, or a :class:`LedsimError` naming ``name`` and the allowed
    ones (``kind``: what they are, e.g. ``"water"``)."""
    try:
        return registry[name]
    except KeyError:
        raise LedsimError(f"unknown {kind} {name!r}: choose one of "
                          f"{', '.join(registry)}") from None

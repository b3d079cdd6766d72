"""``--set KEY=VALUE`` of ``meshcorr batch`` and ``--set METHOD:KEY=VALUE`` of ``meshcorr bench``.

A VALUE is read as a Python literal (:func:`literal_value`); an option that
its method refuses is reported with the --set item that gave it
(:func:`checked_set`), before any work.
"""

from __future__ import annotations

import ast
from typing import Callable

from ..errors import ParameterError

#: The fix named after a --set item that its method refuses.
SET_FIX = ("Correct this --set (its VALUE is read as a Python literal such as 8, 0.5, True or None; other text "
           "is a string, e.g. reorder=greedy), or leave it out to keep the method's default.")


def literal_value(text: str):
    """The Python literal ``text`` spells (``8``, ``0.5``, ``True``, ``None``), else ``text`` itself."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def checked_set(item: str, check: Callable[[], object]) -> None:
    """Run ``check()``, which raises the method's ParameterError for options with --set ``item`` in them.

    The error is raised again as one paragraph: the --set item, the method's message (the
    option, the value, what is allowed) and the fix.
    """
    try:
        check()
    except ParameterError as exc:
        raise ParameterError(f"--set {item!r}: {exc} {SET_FIX}") from None

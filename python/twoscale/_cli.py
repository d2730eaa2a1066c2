"""The command-line conventions of the package's scripts
(``python/examples/*.py``): bad input is one line ``error: …`` on stderr
and a non-zero exit status, never a traceback. Arguments are checked by
argparse (its ``usage: …`` and ``error: …``, status 2) with the types
below; what only shows later (a refused value, a file that cannot be read
or written) is a ``ValueError`` or an ``OSError``, which :func:`run` prints
as ``error: …`` (status 1). Other exceptions are bugs and keep their
traceback.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable


def positive_int(text: str) -> int:
    """An argparse type: an integer ≥ 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {value}")
    return value


def unit_interval(text: str) -> float:
    """An argparse type: a number in (0, 1)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number in (0, 1), got {text!r}") from None
    if not 0.0 < value < 1.0:
        raise argparse.ArgumentTypeError(f"must be a number in (0, 1), got {value}")
    return value


def run(main: Callable[[], object]) -> None:
    """Runs ``main()``; a ``ValueError`` or ``OSError`` is printed as
    ``error: …`` on stderr and exits with status 1."""
    try:
        main()
    except (ValueError, OSError) as error:
        print(f"error: {error}", file=sys.stderr)
        sys.exit(1)

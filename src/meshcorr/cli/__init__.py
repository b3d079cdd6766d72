"""The ``meshcorr`` command line: a thin layer over the library.

Each sub-command lives in its own module with ``add_parser(subparsers)``
and ``run(args) -> int``; this module only dispatches and turns expected
errors into one-line messages with a non-zero exit code.
"""

from __future__ import annotations

import argparse
import sys
import warnings

from .. import __version__
from ..errors import MeshcorrError
from . import batch as _batch
from . import bench as _bench
from . import cache as _cache
from . import embed as _embed
from . import evaluate as _evaluate
from . import match as _match
from . import show as _show
from . import transfer as _transfer

#: Sub-command modules, in the order ``--help`` lists them.
COMMANDS = [_match, _evaluate, _bench, _show, _transfer, _embed, _batch, _cache]

EXIT_USAGE = 2
EXIT_ERROR = 1


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="meshcorr",
        description="Dense vertex-to-vertex correspondence between two 3D triangle meshes "
                    "(spectral method of Jain & Zhang 2006, and its baselines).",
        epilog="Run 'meshcorr COMMAND --help' for the options of one command.",
    )
    parser.add_argument("--version", action="version", version=f"meshcorr {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the Python traceback of unexpected errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in COMMANDS:
        module.add_parser(sub)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None):
    print(f"meshcorr: warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``meshcorr`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    warnings.showwarning = _show_warning
    try:
        return int(args.run(args) or 0)
    except MeshcorrError as exc:
        print(f"meshcorr: error: {exc}", file=sys.stderr)
        return EXIT_USAGE if isinstance(exc, ValueError) else EXIT_ERROR
    except MemoryError:
        print("meshcorr: error: out of memory. The dense pipeline stores n x n matrices; "
              "use smaller meshes (decimate them) or a machine with more memory.", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("meshcorr: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # noqa: BLE001 - the last line of defence against tracebacks
        if args.debug:
            raise
        print(f"meshcorr: internal error: {type(exc).__name__}: {exc}. "
              "Run again with --debug for the traceback and report it.", file=sys.stderr)
        return EXIT_ERROR


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

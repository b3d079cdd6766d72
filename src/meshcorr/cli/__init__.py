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
from ..errors import MeshcorrError, MeshWarning
from ..io import quiet_trimesh
from ..io.files import DISK_FULL, disk_full_message
from ..runtime.interrupt import Terminated
from . import batch as _batch
from . import bench as _bench
from . import cache as _cache
from . import embed as _embed
from . import evaluate as _evaluate
from . import maps as _maps
from . import match as _match
from . import pick as _pick
from . import show as _show
from . import transfer as _transfer
from ._signals import interrupt_once
from .exits import (EXIT_BROKEN_PIPE, EXIT_CODES, EXIT_ERROR, EXIT_FAILED_RUNS, EXIT_INPUT,  # noqa: F401 - the
                    EXIT_INTERRUPTED, EXIT_OK, EXIT_TERMINATED, EXIT_USAGE,  # codes' home before cli.exits
                    exit_code)

#: Sub-command modules, in the order ``--help`` lists them.
COMMANDS = [_match, _evaluate, _bench, _show, _pick, _transfer, _maps, _embed, _batch, _cache]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="meshcorr",
        description="Dense vertex-to-vertex correspondence between two 3D triangle meshes "
                    "(spectral method of Jain & Zhang 2006, and its baselines).",
        epilog="Run 'meshcorr COMMAND --help' for the options of one command.\n\n" + EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"meshcorr {__version__}")
    _add_common_options(parser, default=False)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in COMMANDS:
        module.add_parser(sub)
    for command in sub.choices.values():
        # Also after the command name; SUPPRESS keeps a value given before it.
        _add_common_options(command, default=argparse.SUPPRESS)
        command.epilog = ((command.epilog + "\n\n") if command.epilog else "") + EXIT_CODES
        command.formatter_class = argparse.RawDescriptionHelpFormatter
    return parser


def _add_common_options(parser: argparse.ArgumentParser, *, default) -> None:
    """``--debug``, ``-q`` and ``-v``, before or after the command name (unless it has its own)."""
    def add(*flags, **kwargs):
        if not any(flag in parser._option_string_actions for flag in flags):
            parser.add_argument(*flags, default=default, **kwargs)

    add("--debug", action="store_true", help="show the Python traceback of unexpected errors")
    add("-q", "--quiet", action="store_true", help="no progress or status lines on stderr")
    add("-v", "--verbose", action="store_true",
        help="report every stage with its time as it ends, and where each input came from")


def _show_warning(message, category, filename, lineno, file=None, line=None):
    print(f"meshcorr: warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``meshcorr`` console script.

    ``argv=None`` runs the process's own command line: the run then owns
    the process's SIGINT and SIGTERM handling to its end (:func:`._signals.interrupt_once`).
    """
    with interrupt_once(ignore_after=argv is None):
        args = None
        try:
            parser = build_parser()
            args = parser.parse_args(argv)
            for name in ("debug", "quiet", "verbose"):
                setattr(args, name, bool(getattr(args, name, False)))
            if args.command is None:
                parser.print_help(sys.stderr)
                return EXIT_USAGE
            if args.quiet and args.verbose:
                parser.error("-q/--quiet and -v/--verbose contradict each other; give one")
            with warnings.catch_warnings(), quiet_trimesh():
                warnings.showwarning = _show_warning
                if args.quiet:
                    warnings.simplefilter("ignore", MeshWarning)
                return int(args.run(args) or 0)
        except MeshcorrError as exc:
            print(f"meshcorr: error: {exc}", file=sys.stderr)
            return exit_code(exc)
        except MemoryError:
            print("meshcorr: error: out of memory. The dense pipeline stores n x n matrices; "
                  "use smaller meshes (decimate them) or a machine with more memory.", file=sys.stderr)
            return EXIT_ERROR
        except Terminated:  # SIGTERM: the same cleanup as Ctrl-C
            print("meshcorr: terminated", file=sys.stderr)
            return EXIT_TERMINATED
        except KeyboardInterrupt:
            print("meshcorr: interrupted", file=sys.stderr)
            return EXIT_INTERRUPTED
        except BrokenPipeError:
            # The reader of stdout went away (e.g. '| head'): stop quietly, as other tools do.
            _silence_stdout()
            return EXIT_BROKEN_PIPE
        except Exception as exc:  # noqa: BLE001 - the last line of defence against tracebacks
            if isinstance(exc, OSError) and exc.errno in DISK_FULL:  # stdout, or a file not written atomically
                print(f"meshcorr: error: {_disk_full(exc)}", file=sys.stderr)
                return EXIT_INPUT
            if args is not None and args.debug:
                raise
            print(f"meshcorr: internal error: {type(exc).__name__}: {exc}. "
                  "Run again with --debug for the traceback and report it.", file=sys.stderr)
            return EXIT_ERROR


def _disk_full(exc: OSError) -> str:
    """The message of a full disk met outside :func:`meshcorr.io.atomic_write` (which names its file).

    Such a write error names no file: it is stdout (``--json``, ``-o -`` into a file on a full disk)
    or a temporary file of a library. Data still waiting for stdout is dropped if it does not fit
    either, so that the interpreter's final flush does not fail again.
    """
    if exc.filename is not None:
        return disk_full_message(exc.filename, exc)
    try:
        sys.stdout.flush()
    except (OSError, ValueError):
        _silence_stdout()
    return disk_full_message("stdout (or a temporary file)", exc, removed=False)


def _silence_stdout() -> None:
    """Point stdout at /dev/null, so that the interpreter's final flush does not fail again."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # stdout replaced (tests) or closed
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""``meshcorr cache``: size and location of the prepared-shape cache, and clearing it."""

from __future__ import annotations

import argparse

HELP = "show the size of the prepared-shape cache or clear it"

DESCRIPTION = """\
Prepared shapes (meshcorr.prepare, 'meshcorr batch --cache') are kept in one
folder: $MESHCORR_CACHE, else $XDG_CACHE_HOME/meshcorr, else ~/.cache/meshcorr.
'info' prints its path, file count and size; 'clear' deletes its files.
"""


def add_parser(sub) -> None:
    p = sub.add_parser("cache", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("action", choices=("info", "clear"),
                   help="info: print the folder, its prepared shapes and their size; clear: delete them "
                        "(only meshcorr's own cache files; other files stay)")
    p.add_argument("--dir", metavar="DIR", default=None, help="the cache folder (default: as above)")
    p.set_defaults(run=run)


def _size(n: int) -> str:
    return f"{n / 1024 ** 2:.1f} MiB"


def run(args) -> int:
    from ..shapes.cache import ShapeCache
    from ..errors import OutputError

    cache = ShapeCache(args.dir)
    try:
        info = cache.info() if args.action == "info" else cache.clear()
    except OSError as error:  # an unreadable folder, a file that cannot be removed: was an internal error
        where = f" ({error.filename})" if error.filename else ""
        raise OutputError(f"Cannot {'read' if args.action == 'info' else 'clear'} the cache folder "
                          f"{cache.root}: {error.strerror or error}{where}. Check its permissions, or give "
                          "another folder with --dir.") from None
    missing = "" if cache.root.is_dir() else " (the folder does not exist yet)"
    if args.action == "info":
        print(f"{info['path']}: {info['files']} prepared shapes, {_size(info['bytes'])}{missing}")
    else:
        print(f"{info['path']}: removed {info['files']} prepared shapes, {_size(info['bytes'])}{missing}")
    return 0

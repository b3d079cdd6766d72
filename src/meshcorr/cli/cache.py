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
    p.add_argument("action", choices=("info", "clear"))
    p.add_argument("--dir", metavar="DIR", default=None, help="the cache folder (default: as above)")
    p.set_defaults(run=run)


def _size(n: int) -> str:
    return f"{n / 1024 ** 2:.1f} MiB"


def run(args) -> int:
    from ..cache import ShapeCache

    cache = ShapeCache(args.dir)
    if args.action == "info":
        info = cache.info()
        print(f"{info['path']}: {info['files']} prepared shapes, {_size(info['bytes'])}")
    else:
        info = cache.clear()
        print(f"{info['path']}: removed {info['files']} prepared shapes, {_size(info['bytes'])}")
    return 0

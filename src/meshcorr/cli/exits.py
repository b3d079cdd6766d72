"""The exit codes of the ``meshcorr`` command, and the text ``--help`` lists them in.

Every command module takes its codes from here (not from :mod:`meshcorr.cli`,
which imports the commands): the README lists the same codes.
"""

from __future__ import annotations

from ..errors import DiskFullError, InputError, MeshcorrError, MeshError

EXIT_OK = 0
EXIT_ERROR = 1  # an internal error or out of memory
EXIT_USAGE = 2  # bad usage: an unknown flag, a bad option value, an output that cannot be written
EXIT_INPUT = 3  # bad input data: a mesh, map or ground-truth file that cannot be used; or a full disk
EXIT_FAILED_RUNS = 4  # 'bench', 'batch': some runs failed (recorded in their results)
EXIT_INTERRUPTED = 130  # Ctrl-C (SIGINT); no output file is left behind
EXIT_TERMINATED = 143  # SIGTERM (kill, a job scheduler's time limit), as 128 + 15; handled as Ctrl-C
EXIT_BROKEN_PIPE = 141  # stdout closed early (piped into 'head'), as 128 + SIGPIPE

EXIT_CODES = f"""\
exit codes:
  {EXIT_OK}    success
  {EXIT_ERROR}    internal error or out of memory
  {EXIT_USAGE}    bad usage: unknown flag, bad option value, an output that cannot be written
  {EXIT_INPUT}    bad input data: a mesh, map or ground-truth file that cannot be used;
       or the disk (or quota) was full while writing an output (a file: none is left)
  {EXIT_FAILED_RUNS}    bench, batch: some runs failed (recorded in their results)
  {EXIT_INTERRUPTED}  interrupted (Ctrl-C); no output file is written (batch keeps the maps it finished)
  {EXIT_TERMINATED}  terminated (SIGTERM), as interrupted
  {EXIT_BROKEN_PIPE}  stdout was closed early (e.g. piped into head)
"""


def exit_code(error: MeshcorrError) -> int:
    """The exit code of an expected error: bad input data or a full disk (3), or bad usage (2)."""
    if isinstance(error, (MeshError, InputError, DiskFullError)):
        return EXIT_INPUT
    return EXIT_USAGE if isinstance(error, ValueError) else EXIT_ERROR

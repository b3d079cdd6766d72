"""What every layer needs to run: checks, threads, interrupts, timing, progress, memory.

- :mod:`~meshcorr.runtime.checks`: parameter checks with one message shape
  ("The 'k' parameter must be an int >= 2. Got 1 instead."), and the one
  check of a vertex map;
- :mod:`~meshcorr.runtime.threads`: worker threads, one BLAS thread each;
- :mod:`~meshcorr.runtime.interrupt`: Ctrl-C honoured inside long loops;
- :mod:`~meshcorr.runtime.timing`: the stages' timer and progress callback;
- :mod:`~meshcorr.runtime.progress`: progress bars (tqdm) and lines (stderr);
- :mod:`~meshcorr.runtime.memory`: the memory budget (``max_memory``);
- :mod:`~meshcorr.runtime.messages`: an error in one line.

The bottom layer: it imports nothing of meshcorr but :mod:`meshcorr.errors`.
"""

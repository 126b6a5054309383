"""The worker side: what runs in the worker processes and the pool that runs it.

- :mod:`.pool`: the fixed pool of killable worker processes (time limit, resident-memory
  watchdog, recycling), used from asyncio; :mod:`.process`, the loop each one runs;
- :mod:`.jobs`: one shape's job as a worker runs it (read, budget, prune, serialise), and
  the warm-up that loads the compiled kernels;
- :mod:`.match_job`: a match's job (two shapes pruned alike, matched);
- :mod:`.compile`: ``python -m service.compile``, the kernels compiled ahead;
- :mod:`.numba_seed`: numba's cache seeded from the image's, before anything compiles.

Nothing here knows HTTP: a job comes in as checked options and data, and goes back as
a serialised body.
"""

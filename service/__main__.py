"""``python -m service``: serve on SKELPRUNE_HOST:SKELPRUNE_PORT."""

from __future__ import annotations

import logging
import logging.config
import os
import signal
import sys
from types import FrameType

import uvicorn
from pydantic import ValidationError

from service.logs import logging_config
from service.numba_seed import seed_numba_cache
from service.settings import Settings, settings_error


def _exit_cleanly(signum: int, frame: FrameType | None) -> None:
    sys.exit(0)


def main() -> None:
    """Read the settings from the environment and run uvicorn (one process; the
    pruning work is spread over the app's own worker pool)."""
    try:
        settings = Settings()
    except ValidationError as exc:  # one line naming the variable, not a traceback
        print(f"error: {settings_error(exc)}", file=sys.stderr)
        sys.exit(2)
    logging.config.dictConfig(logging_config(settings.log_level))  # uvicorn sets it again
    cache = os.environ.get("NUMBA_CACHE_DIR")
    if settings.numba_cache_seed and cache:
        # before the pool starts: its workers read the cache when they warm up
        copied = seed_numba_cache(settings.numba_cache_seed, cache)
        logging.getLogger("service").info("numba cache seeded: %d files", copied)
    from service.app import create_app  # only now: importing it already compiles

    # uvicorn drains in-flight requests and closes the pool on SIGTERM/SIGINT, then
    # re-raises the signal under the handlers it found. These make that final step a
    # clean exit 0 (what `docker stop` and Kubernetes expect) instead of death by signal.
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, _exit_cleanly)
    uvicorn.run(
        create_app(settings), host=settings.host, port=settings.port,
        log_level=settings.log_level,
        log_config=logging_config(settings.log_level),  # JSON lines on stderr
        access_log=False,  # the service writes its own access log, with request IDs
        # http: uvicorn's default picks httptools (the service extra) and falls back to h11
        # a drain after SIGTERM is bounded: below the orchestrator's grace period
        timeout_graceful_shutdown=settings.shutdown_timeout,
    )


if __name__ == "__main__":
    main()

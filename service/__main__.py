"""``python -m service``: serve on SKELPRUNE_HOST:SKELPRUNE_PORT."""

from __future__ import annotations

import uvicorn

from service.app import create_app
from service.settings import Settings


def main() -> None:
    """Read the settings from the environment and run uvicorn (one process; the
    pruning work is spread over the app's own worker pool)."""
    settings = Settings()
    uvicorn.run(
        create_app(settings), host=settings.host, port=settings.port,
        log_level=settings.log_level,
    )


if __name__ == "__main__":
    main()

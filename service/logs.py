"""Structured logs: one JSON object per line, for the service's and uvicorn's loggers.

Each record carries ``time`` (UTC, ISO 8601), ``level``, ``logger`` and ``message``,
plus any ``extra`` fields the caller gave (the access log adds ``method``, ``path``,
``status``, ``duration_ms``, ``request_id``, ``client``). An exception is logged as its
type name (``error``); its traceback only with ``tracebacks=True`` (the service turns
that on at ``SKELPRUNE_LOG_LEVEL=debug``), so a production log never carries a stack
trace. Nothing secret is ever passed to a logger: the access log records no headers and
no query string.
"""

from __future__ import annotations

import contextvars
import datetime as dt
import json
import logging
import traceback
from typing import Any

#: The current request's ID: set by the request middleware (:mod:`service.http.request_context`),
#: read by problem bodies and log records.
request_id_var: contextvars.ContextVar[str | None] = contextvars.ContextVar(
    "skelprune_request_id", default=None
)

__all__ = ["JsonFormatter", "logging_config", "request_id_var"]

#: Attributes every LogRecord has; anything else on a record came in through ``extra``.
_STANDARD = set(vars(logging.LogRecord("", 0, "", 0, "", (), None))) | {"message", "asctime"}
# uvicorn's own extras that repeat what the message says
_DROP = {"color_message"}


class JsonFormatter(logging.Formatter):
    """Format a record as one line of JSON.

    Parameters
    ----------
    tracebacks : bool
        Add the formatted traceback of ``exc_info`` (field ``traceback``). Off by
        default: only the exception's type goes out (field ``error``).
    """

    def __init__(self, tracebacks: bool = False) -> None:
        super().__init__()
        self.tracebacks = tracebacks

    def format(self, record: logging.LogRecord) -> str:
        doc: dict[str, Any] = {
            "time": dt.datetime.fromtimestamp(record.created, dt.UTC)
            .isoformat(timespec="milliseconds")
            .replace("+00:00", "Z"),
            "level": record.levelname,
            "logger": record.name,
            "message": record.getMessage(),
        }
        for key, value in vars(record).items():
            if key not in _STANDARD and key not in _DROP and not key.startswith("_"):
                doc[key] = value
        rid = request_id_var.get()
        if rid is not None:  # any line logged while serving a request names it
            doc.setdefault("request_id", rid)
        if record.exc_info and record.exc_info[0] is not None:
            doc["error"] = record.exc_info[0].__name__
            if self.tracebacks:
                doc["traceback"] = "".join(traceback.format_exception(*record.exc_info))
        return json.dumps(doc, default=str, ensure_ascii=False)


def logging_config(level: str, *, tracebacks: bool | None = None) -> dict[str, Any]:
    """``logging.config.dictConfig`` mapping for uvicorn: every line JSON, on stderr.

    Parameters
    ----------
    level : str
        ``critical`` … ``debug``: the level of the service's and uvicorn's loggers.
    tracebacks : bool, optional
        Include tracebacks; default: only at ``debug``.
    """
    name = level.upper()
    if tracebacks is None:
        tracebacks = name == "DEBUG"
    return {
        "version": 1,
        "disable_existing_loggers": False,
        "formatters": {"json": {"()": JsonFormatter, "tracebacks": tracebacks}},
        "handlers": {
            "stderr": {
                "class": "logging.StreamHandler",
                "formatter": "json",
                "stream": "ext://sys.stderr",
            }
        },
        "loggers": {
            "uvicorn": {"handlers": ["stderr"], "level": name, "propagate": False},
            "uvicorn.error": {"level": name},
            "uvicorn.access": {"handlers": ["stderr"], "level": name, "propagate": False},
            "service": {"handlers": ["stderr"], "level": name, "propagate": False},
        },
    }

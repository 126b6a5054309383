"""Running the skelprune library's command line in its own Python: where that Python is,
and one run, cancellable, its errors passed to the algorithm's feedback."""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from typing import Any

from qgis.core import QgsProcessingException

#: The environment variable, and the QGIS setting, naming the Python skelprune is in.
PYTHON_VARIABLE = "SKELPRUNE_PYTHON"
PYTHON_SETTING = "skelprune/python"
#: What to tell a user whose configured Python has no skelprune.
NOT_FOUND = (
    "no Python with skelprune found: install skelprune (pip install 'skelprune[geo]') in "
    "a Python environment and name that environment's python in the SKELPRUNE_PYTHON "
    "environment variable or the QGIS setting skelprune/python (docs/qgis.md)"
)


def python() -> str:
    """The configured Python executable (checked to exist), else a clear error."""
    where = os.environ.get(PYTHON_VARIABLE)
    if not where:
        from qgis.core import QgsSettings

        where = QgsSettings().value(PYTHON_SETTING, "") or None
    if not where:
        raise QgsProcessingException(NOT_FOUND)
    found = shutil.which(where)
    if found is None:
        raise QgsProcessingException(f"{PYTHON_VARIABLE}={where}: no such program; {NOT_FOUND}")
    return found


def run(arguments: list[str], feedback: Any, allowed: tuple[int, ...] = (0,)) -> str:
    """``python -m skelprune.cli ARGUMENTS``: its standard output. Each line it writes on
    stderr goes to the feedback (errors as errors); a run that ends with a status not in
    ``allowed``, or is cancelled, is a :class:`QgsProcessingException` with its last
    message."""
    command = [python(), "-m", "skelprune.cli", *arguments]
    feedback.pushCommandInfo(" ".join(command))
    proc = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, encoding="utf-8"
    )
    while proc.poll() is None:
        if feedback.isCanceled():
            proc.kill()
            proc.wait()
            raise QgsProcessingException("cancelled")
        time.sleep(0.1)
    out, err = proc.communicate()
    lines = [line for line in err.splitlines() if line.strip()]
    for line in lines:
        if line.startswith("error:"):
            feedback.reportError(line)
        else:
            feedback.pushInfo(line)
    if proc.returncode not in allowed:
        last = lines[-1] if lines else f"exit status {proc.returncode}"
        if "No module named skelprune" in err:
            last = NOT_FOUND
        raise QgsProcessingException(last)
    return out

"""Commands at once: how long a fresh process takes to answer the simplest requests.

Fresh processes, started as a user starts them, with the kernels compiled ahead
(``make setup``):

- ``skelprune --help`` and ``skelprune --version`` (the console script);
- ``python -c "import skelprune"``: the package alone;
- a fresh ``python`` process: its imports (numpy, PIL, skelprune and the pipeline,
  ``from skelprune import prune``) and then its first ``prune()`` of a small shape
  (kimia216's bird-2), and the two together;
- and, as the floor under all of them, ``python -c pass``.

The medians of several rounds, the rounds interleaved so that a slow spell of the
machine hits every row alike. Also lists which heavy modules ``import skelprune`` and
the imports of a first ``prune()`` load.

``python -m benchmarks commands`` (about half a minute).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from testkit import REPO

from .common import DATA, table

ROUNDS = 7
SCRIPT = Path(sys.executable).with_name("skelprune")

FIRST_PRUNE = """
import time
t0 = time.perf_counter()
import numpy as np
from PIL import Image
from skelprune import prune
t1 = time.perf_counter()
mask = np.asarray(Image.open({path!r})) > 0
prune(mask).to_dict()
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""

HEAVY = ("numba", "scipy", "scipy.ndimage", "scipy.optimize", "PIL", "cv2", "shapely", "rich")
LOADED = """
import json, sys
import skelprune
alone = [m for m in {heavy!r} if m in sys.modules]
from skelprune import prune
print(json.dumps([alone, [m for m in {heavy!r} if m in sys.modules]]))
"""


def _seconds(cmd: list[str]) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, cwd=REPO, capture_output=True, check=True)
    return time.perf_counter() - t


def main() -> None:
    bird = str(DATA / "kimia216" / "bird-2.png")
    commands = {
        "`python -c pass` (the floor)": [sys.executable, "-c", "pass"],
        "`skelprune --help`": [str(SCRIPT), "--help"],
        "`skelprune --version`": [str(SCRIPT), "--version"],
        "`python -c 'import skelprune'`": [sys.executable, "-c", "import skelprune"],
    }
    times: dict[str, list[float]] = {name: [] for name in commands}
    imports, first, both = [], [], []
    for _ in range(ROUNDS):
        for name, cmd in commands.items():
            times[name].append(_seconds(cmd))
        out = subprocess.run(
            [sys.executable, "-c", FIRST_PRUNE.format(path=bird)],
            cwd=REPO,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        a, b = map(float, out.split())
        imports.append(a)
        first.append(b)
        both.append(a + b)
    times["fresh process: imports (numpy, PIL, the pipeline)"] = imports
    times["fresh process: then its first `prune()` (bird-2)"] = first
    times["fresh process: imports and first `prune()`"] = both
    rows = [
        [name, f"{np.median(v):.2f}", f"{min(v):.2f}–{max(v):.2f}"] for name, v in times.items()
    ]
    print(table(["what (fresh processes)", "seconds, median", f"range of {ROUNDS}"], rows))
    alone, pipeline = json.loads(
        subprocess.run(
            [sys.executable, "-c", LOADED.format(heavy=HEAVY)],
            cwd=REPO,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    )
    print(f"\nheavy modules after `import skelprune`: {', '.join(alone) or 'none'}")
    print(f"after `from skelprune import prune`: {', '.join(pipeline) or 'none'}")

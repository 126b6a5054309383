"""Run the benchmarks named on the command line (default: all) and print their tables."""

from __future__ import annotations

import importlib
import pkgutil
import sys

import benchmarks


def main(argv: list[str]) -> None:
    known = sorted(
        m.name[len("bench_") :]
        for m in pkgutil.iter_modules(benchmarks.__path__)
        if m.name.startswith("bench_")
    )
    unknown = [a for a in argv if a not in known]
    if unknown:
        print(
            f"usage: python -m benchmarks [{' | '.join(known)}] ... (unknown: {' '.join(unknown)})",
            file=sys.stderr,
        )
        sys.exit(2)
    for name in argv or known:
        print(f"\n## {name}\n", flush=True)
        importlib.import_module(f"benchmarks.bench_{name}").main()


if __name__ == "__main__":
    main(sys.argv[1:])

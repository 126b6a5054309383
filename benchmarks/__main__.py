"""Run the benchmarks named on the command line (default: all) and print their tables."""

from __future__ import annotations

import importlib
import pkgutil
import sys

import benchmarks


def main(argv: list[str]) -> None:
    names = argv or sorted(m.name[len("bench_"):] for m in pkgutil.iter_modules(benchmarks.__path__)
                           if m.name.startswith("bench_"))
    for name in names:
        print(f"\n## {name}\n", flush=True)
        importlib.import_module(f"benchmarks.bench_{name}").main()


if __name__ == "__main__":
    main(sys.argv[1:])

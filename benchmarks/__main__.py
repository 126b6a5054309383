"""Run the benchmarks named on the command line (default: all) and print their tables.

Arguments after a benchmark's name that are not benchmark names are its own (``python -m
benchmarks default --quick --data DIR``); they go to its ``main(argv)``, for the
benchmarks whose ``main`` takes ``argv``.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import sys

import benchmarks


def _split(argv: list[str], known: list[str]) -> list[tuple[str, list[str]]]:
    """``[(name, its arguments), ...]``: the arguments after a name are that benchmark's,
    up to the next name that does not follow an option (``--only networks`` is an
    option's value, not the networks benchmark).

    >>> _split(["default", "--only", "networks", "limbs"], ["default", "limbs", "networks"])
    [('default', ['--only', 'networks']), ('limbs', [])]
    """
    runs: list[tuple[str, list[str]]] = []
    for i, a in enumerate(argv):
        after_option = i > 0 and argv[i - 1].startswith("-") and "=" not in argv[i - 1]
        if a in known and not (runs and after_option):
            runs.append((a, []))
        elif runs:
            runs[-1][1].append(a)
        else:
            raise ValueError(a)
    return runs


def main(argv: list[str]) -> None:
    known = sorted(
        m.name[len("bench_") :]
        for m in pkgutil.iter_modules(benchmarks.__path__)
        if m.name.startswith("bench_")
    )
    try:
        runs = _split(argv, known) if argv else [(name, []) for name in known]
    except ValueError as e:
        print(
            f"usage: python -m benchmarks [{' | '.join(known)}] [ARGS] ... (unknown: {e})",
            file=sys.stderr,
        )
        sys.exit(2)
    for name, args in runs:
        print(f"\n## {name}\n", flush=True)
        bench = importlib.import_module(f"benchmarks.bench_{name}").main
        takes_arguments = "argv" in inspect.signature(bench).parameters
        if args and not takes_arguments:
            print(
                f"python -m benchmarks {name} takes no arguments ({' '.join(args)})",
                file=sys.stderr,
            )
            sys.exit(2)
        if args:
            bench(argv=args)
        else:
            bench()  # as it always ran


if __name__ == "__main__":
    main(sys.argv[1:])

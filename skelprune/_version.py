"""The versions: the one place each is written (pyproject.toml reads ``__version__``)."""

#: The package version (library, command line and service).
__version__ = "0.1.0"

#: The version of the results: raised whenever the same input and options may give a
#: different skeleton or different numbers (a change of the medial axis, the pruning, a
#: default), and only then; a release that changes no output keeps it.
ALGORITHM_VERSION = "2"

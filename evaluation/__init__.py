"""The evaluation behind ``make eval``: the paper's tables and figures, the stability
benchmark and its perturbations (:mod:`.perturb`), and the skeletonize + cut baseline.

Not part of the pipeline: nothing in it is imported by :func:`skelprune.prune`.
"""

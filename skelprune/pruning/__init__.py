"""Pruning: from the medial axis's graph to the chosen skeleton.

- :mod:`.coarse`: the coarse stage (``coarse="dce"``), DCE contour-partition pruning
  made robust to boundary noise;
- :mod:`.bayesian`: the greedy Bayesian sequence and its ``argmin λ`` (docs/algorithm.md);
- :mod:`.dce`: Discrete Curve Evolution and the contour partition (docs/algorithm.md), used by
  the coarse stage and by ``method="dce"``; :mod:`._generating` tells which boundary
  segments generate each skeleton point.
"""

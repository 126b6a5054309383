"""Pruning: from the medial axis's graph to the chosen skeleton.

- :mod:`.coarse`: the coarse stage (``coarse="dce"``), DCE contour-partition pruning
  made robust to boundary noise;
- :mod:`.bayesian`: the greedy Bayesian sequence and its ``argmin λ`` (SPEC §2.4);
- :mod:`.dce`: Discrete Curve Evolution and the contour partition (SPEC §2.5), used by
  the coarse stage and by ``method="dce"``; :mod:`._generating` tells which boundary
  segments generate each skeleton point.
"""

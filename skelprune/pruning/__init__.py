"""Pruning on any grid: from a medial axis's branch graph to the chosen skeleton.

The modules here know no grid: they speak to one through the protocols of :mod:`.grid`
(docs/algorithm.md, "The grid interface"), and ``tests/library/test_layers.py`` checks
that none imports :mod:`skelprune.grid`, :mod:`skelprune.grid3d` or
:mod:`skelprune.skeleton`, directly or through another module.

- :mod:`.branch_graph` (with the compiled :mod:`._trace`): the one branch graph of every
  grid, over points with a neighbour table and step kinds;
- :mod:`.bayesian`: the greedy Bayesian sequence and its ``argmin λ`` (docs/algorithm.md);
- :mod:`.choice`: the choice of step; :mod:`.margin`: the answer's branch margins;
  :mod:`.log`: what each step of a sequence removed and merged;
- :mod:`.normalisation` (seed, ``ℓ̄``, ``α``), :mod:`.tip_cuts` (the tips' rule and
  order), :mod:`.limb_memory` (what the limb tests keep): each grid gives its counts.

The stages that hold in the plane only (the coarse DCE stage, DCE pruning, the tips' cut
and the limbs' test on disks) live with the pixel grid, in :mod:`skelprune.grid`.
"""

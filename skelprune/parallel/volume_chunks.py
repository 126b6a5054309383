"""A label volume larger than memory, pruned on Dask from its Zarr store, chunk by chunk.

Two passes of tasks, each reading only its part of the store:

1. **boxes**: one task a chunk of the array (:func:`skelprune.io.zarr.chunk_boxes`) groups
   the chunk's voxels by label (:func:`skelprune.volume_labels.label_groups`) and answers
   each label's box and voxel count there; the client takes each label's union of boxes;
2. **labels**: one task a batch of labels reads each label's box from the store, splits
   the label into its 26-connected pieces and prunes them, as :func:`skelprune.prune`
   does for the whole array.

A label's box is the same whether found chunk by chunk or in one pass, so the answer is
the unchunked one, component for component. A worker holds one chunk (pass 1) or one
label's box (pass 2) at a time: its memory is bounded by the chunk size and the largest
label's box, which ``max_box_voxels`` caps (a label wider than that is refused before
pass 2; splitting one label across workers is not done, docs/volumes.md).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import EmptyMaskError, ImageTooLargeError, InvalidOptionError
from ..options import OutputOptions, PruneOptions, VolumeOptions
from ..volume_parallel import in_batches, map_batches

if TYPE_CHECKING:
    from ..output.volume import VolumeResult

__all__ = ["MAX_BOX_VOXELS", "prune_zarr_chunked"]

#: The default cap on one label's box (voxels): what a worker reads at once in pass 2.
MAX_BOX_VOXELS = 1 << 27


def _chunk_labels(path: str, box: tuple[slice, slice, slice]) -> tuple[np.ndarray, np.ndarray]:
    """Pass 1: the labels of one chunk, their boxes in the volume's frame and counts."""
    from ..io.zarr import open_zarr_volume
    from ..volume_labels import label_groups

    part = open_zarr_volume(path).read(box)
    if part.dtype == np.bool_:
        part = part.view(np.uint8)
    g = label_groups(part)
    values = np.array(g.values, dtype=object)
    shift = np.array([box[0].start, box[1].start, box[2].start] * 2, np.int64)
    counts = np.diff(g.starts)
    boxes = np.concatenate([g.boxes + shift, counts[:, None]], axis=1)
    return values, boxes


def _prune_labels(
    labels: list[tuple[int, tuple[int, ...]]],
    path: str,
    options: PruneOptions,
    spacing: tuple[float, float, float],
    binary: bool,
) -> list[Any]:
    """Pass 2: each label's box read from the store, its pieces pruned in order."""
    from scipy import ndimage

    from ..grid3d.distance import pad
    from ..io.zarr import open_zarr_volume
    from ..volume_parallel import prune_volume_component

    store = open_zarr_volume(path)
    cube = np.ones((3, 3, 3), bool)
    out = []
    for value, b in labels:
        region = store.read((slice(b[0], b[3] + 1), slice(b[1], b[4] + 1), slice(b[2], b[5] + 1)))
        mask = region != 0 if binary else region == value
        del region
        lab, _ = ndimage.label(mask, structure=cube)
        for k, piece in enumerate(ndimage.find_objects(lab), start=1):
            if piece is None:
                continue
            crop = pad(lab[piece] == k)
            origin = (
                b[0] + piece[0].start - 1,
                b[1] + piece[1].start - 1,
                b[2] + piece[2].start - 1,
            )
            component = prune_volume_component(crop, origin, options, spacing)
            component.label = None if binary else value
            out.append(component)
    return out


def _merge(parts: list[tuple[np.ndarray, np.ndarray]]) -> dict[int, list[int]]:
    """Each label's union of boxes and its voxel count over the chunks."""
    merged: dict[int, list[int]] = {}
    for values, boxes in parts:
        for v, b in zip(values.tolist(), boxes.tolist(), strict=True):
            have = merged.get(v)
            if have is None:
                merged[v] = list(b)
            else:
                for i in range(3):
                    have[i] = min(have[i], b[i])
                    have[i + 3] = max(have[i + 3], b[i + 3])
                have[6] += b[6]
    return merged


def prune_zarr_chunked(
    path: str | os.PathLike[str],
    client: Any,
    options: PruneOptions | None = None,
    volume: VolumeOptions | None = None,
    output: OutputOptions | None = None,
    *,
    max_box_voxels: int = MAX_BOX_VOXELS,
    batch_voxels: int = 1 << 22,
    progress: Any = None,
) -> VolumeResult:
    """Prune a Zarr / OME-Zarr label volume on a Dask cluster, one chunk or label a task.

    Parameters
    ----------
    path
        The store (every worker reads it: a path they all see).
    client : dask.distributed.Client or str
        The cluster (a client or a scheduler's address).
    options, volume, output
        As for :func:`skelprune.prune` (OME-Zarr's scale is the spacing unless
        ``volume`` gives one).
    max_box_voxels : int
        The most voxels a label's box may hold (what one task reads at once).
    batch_voxels : int
        Labels go to tasks in batches of at most about this many labelled voxels (and
        at least four batches a worker).
    progress : callable, optional
        Called with the count of labels done as each batch finishes.

    Returns
    -------
    VolumeResult
        The components :func:`skelprune.prune` gives for the whole array, in its order.

    Raises
    ------
    ImageTooLargeError
        A label whose box holds more than ``max_box_voxels`` voxels.
    EmptyMaskError
        No voxel inside.
    """
    from dask.distributed import Client

    from ..io.zarr import chunk_boxes, open_zarr_volume
    from ..output.volume import VolumeResult

    store = open_zarr_volume(path)
    applied = (options or PruneOptions()).resolved()
    if applied.method != "bayesian" or applied.scope != "global":
        raise InvalidOptionError("a volume is pruned with method='bayesian', scope='global'")
    spacing = (volume or VolumeOptions()).spacing
    if store.spacing is not None and spacing == VolumeOptions().spacing:
        spacing = store.spacing
    own = isinstance(client, str)
    dask_client = Client(client) if own else client
    where = os.fspath(path)
    try:
        boxes = list(chunk_boxes(store))
        parts = dask_client.gather(
            [dask_client.submit(_chunk_labels, where, b, pure=False) for b in boxes]
        )
        merged = _merge(parts)
        if not merged:
            raise EmptyMaskError("the volume has no voxel inside")
        binary = set(merged) <= {1}  # a bool or 0/1 volume: one shape, as prune reads it
        for v, b in merged.items():
            size = (b[3] - b[0] + 1) * (b[4] - b[1] + 1) * (b[5] - b[2] + 1)
            if size > max_box_voxels:
                raise ImageTooLargeError(
                    f"label {v}'s box holds {size} voxels, more than max_box_voxels="
                    f"{max_box_voxels} (what one task reads at once)"
                )
        # at least four batches a worker, so that every worker has labels to prune
        n_workers = max(len(dask_client.scheduler_info().get("workers", {})), 1)
        total = sum(b[6] for b in merged.values())
        target = min(batch_voxels, max(total // (4 * n_workers), 1))
        order = sorted(merged)
        labels = [(v, tuple(merged[v][:6])) for v in order]
        batches = in_batches(labels, [merged[v][6] for v in order], target)
        components = map_batches(
            _prune_labels,
            batches,
            (where, applied, spacing, binary),
            client=dask_client,
            progress=progress,
        )
    finally:
        if own:
            dask_client.close()
    mask = np.zeros(store.shape, bool)  # the overlay's mask: one byte a voxel, client side
    for chunk in boxes:
        mask[chunk] = store.read(chunk) != 0
    result = VolumeResult(
        shape=(int(store.shape[0]), int(store.shape[1]), int(store.shape[2])),
        spacing=spacing,
        options=applied,
        output=OutputOptions() if output is None else output,
        volume=mask,
    )
    result.components.extend(components)
    return result

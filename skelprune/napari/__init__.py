"""The napari plugin: a dock widget that prunes the selected Labels or Image layer (2-D
or 3-D) and adds the answer as layers, and sample data to try it on (docs/napari.md).

Installed by the ``napari`` extra (``pip install 'skelprune[napari]'``); napari finds it
through the ``napari.manifest`` entry point (``napari.yaml`` beside this file). It calls
only the public library: :func:`skelprune.prune` and its result objects.
"""

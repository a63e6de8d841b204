"""The material a colour-map operator edits and how a failed edit is undone:
the active material (BakeError when it cannot be edited) and Rollback,
which records its node tree and the data blocks before the edit and puts
them back after a failure. Used by the bake (operators.py) and the surface
filters (surface_filter.py)."""

import bpy

from . import sample_count
from ..compat import uses_nodes


class BakeError(ValueError):
    """A problem the user can fix; its message goes to the operator report
    (a ValueError, like the core's bad input: errors.CORE_ERRORS)."""


def active_material(context):
    """The material of the context (the Properties editor's), else the active
    object's active material, or None."""
    obj = context.object
    return getattr(context, "material", None) or (obj.active_material if obj else None)


def editable_material(context):
    """The active material, if an operator may edit its node tree; else BakeError."""
    material = active_material(context)
    if material is None:
        raise BakeError("No active material: select an object with a material")
    if material.library is not None:
        raise BakeError(f"Material '{material.name}' is linked from the library '{material.library.filepath}' "
                        "and is read-only: make it local first (nothing was changed)")
    if not uses_nodes(material):
        raise BakeError(f"Material '{material.name}' does not use nodes: there is no ColorRamp to filter")
    return material


class Rollback:
    """What an edit may change, recorded before it starts: the tree's nodes
    and links, the state of the node it replaces (`node`: muted, labelled,
    moved aside) and the image and node-group data blocks. `tree` and `node`
    may be None (a lookup baked from an image edits no tree). restore() puts
    them back: new nodes go (with their Samples driver, so none is left
    pointing at a removed node), lost links come back, new data blocks are
    removed."""

    def __init__(self, tree, node):
        self.tree, self.node = tree, node
        self.nodes = {n.name for n in tree.nodes} if tree is not None else set()
        self.links = [(l.from_socket, l.to_socket) for l in tree.links] if tree is not None else []
        self.node_state = (node.mute, node.label, tuple(node.location)) if node is not None else None
        self.images = set(bpy.data.images[:])
        self.groups = set(bpy.data.node_groups[:])

    def restore(self):
        if self.tree is not None:
            for node in [n for n in self.tree.nodes if n.name not in self.nodes]:
                sample_count.remove_driver(node)
                self.tree.nodes.remove(node)
            for from_socket, to_socket in self.links:
                if not any(l.from_socket == from_socket for l in to_socket.links):
                    self.tree.links.new(from_socket, to_socket)
            self.node.mute, self.node.label, self.node.location = self.node_state
        for group in [g for g in bpy.data.node_groups if g not in self.groups]:
            bpy.data.node_groups.remove(group)
        for image in [i for i in bpy.data.images if i not in self.images]:
            bpy.data.images.remove(image)

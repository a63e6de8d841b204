"""Node-group sockets through both of Blender's APIs: 3.x `group.inputs` /
`group.outputs`, 4.x `group.interface.new_socket`, and a node's inputs by
identifier, which 4.x needs for unavailable sockets. Everything else about
node groups is the same in 3.4 and 4.5."""

import bpy

HAS_INTERFACE = bpy.app.version >= (4, 0, 0)


def add_socket(group, name, in_out, socket_type, default=None, min_value=None, max_value=None):
    """A group input ('INPUT') or output ('OUTPUT') socket of `socket_type`
    ('NodeSocketFloat', 'NodeSocketColor', 'NodeSocketVector', 'NodeSocketGeometry')."""
    if HAS_INTERFACE:
        socket = group.interface.new_socket(name, in_out=in_out, socket_type=socket_type)
    else:
        sockets = group.inputs if in_out == "INPUT" else group.outputs
        socket = sockets.new(socket_type, name)
    if default is not None and hasattr(socket, "default_value"):
        socket.default_value = default
    if min_value is not None and hasattr(socket, "min_value"):
        socket.min_value = min_value
    if max_value is not None and hasattr(socket, "max_value"):
        socket.max_value = max_value
    return socket


def socket_names(group, in_out):
    """Names of a group's input or output sockets, in order, in either API."""
    if HAS_INTERFACE:
        return [item.name for item in group.interface.items_tree
                if getattr(item, "item_type", "SOCKET") == "SOCKET" and item.in_out == in_out]
    return [s.name for s in (group.inputs if in_out == "INPUT" else group.outputs)]


def input_socket(node, identifier):
    """The input socket with this identifier, or None. Looking an input up by
    name fails in 4.x for a socket the node's settings make unavailable (W of
    3D noise, Offset of fBm), so search the identifiers."""
    for socket in node.inputs:
        if socket.identifier == identifier:
            return socket
    return None

"""What really drives a node input, as Blender evaluates the tree: the one
walker every reader of a node tree uses (the World reader, the colour map's
ramp and noise readers), so that they agree on what a link means.

Before a renderer sees a shader tree Blender flattens it (ntreeLocalize and
ntree_shader_groups_flatten, source/blender/nodes/shader/node_shader_tree.cc;
Cycles' add_nodes, intern/cycles/blender/shader.cpp):
- a link counts only if it is valid (not part of a cycle, types that
  convert), not muted, and both its sockets are available (`enabled`);
- a reroute and a muted node are removed, each downstream link relinked to
  what fed the input its internal link comes from (nodeInternalRelink);
  `node.internal_links` is Blender's own choice of that input;
- a group node is replaced by its tree: its output is what feeds the
  matching input of the group's active Group Output node, and a Group Input
  node's output inside is what feeds the group node's matching input.
When nothing is left at the end (a reroute with nothing behind it, a muted
node whose output has no internal link, an unlinked Group Output input), the
links through it are dropped and the input it stood for keeps its own value.
These are the shader trees' rules, the only trees Penumbra reads."""

# How far a walk may go (reroutes, groups) before the tree is declared cyclic;
# Blender itself refuses a group that contains itself.
MAX_STEPS = 1000


class NodeTreeCycle(ValueError):
    """A walk did not end: groups nested in themselves."""


class Feed:
    """What drives an input socket.

    node, output  the node and its output socket that drive it; both None
                  when nothing does
    socket        the input whose own value Blender uses when nothing does:
                  the starting input, or one further along the walk (the
                  group node's input behind a Group Input, the Group Output's
                  input inside a group); when something does, the input it
                  is linked to
    path          the group nodes the driver sits inside, outermost first,
                  relative to where the walk started (() : the same tree)"""

    def __init__(self, node, output, socket, path):
        self.node, self.output, self.socket, self.path = node, output, socket, path

    def __repr__(self):
        where = self.output.identifier if self.output is not None else f"own value of {self.socket.identifier}"
        inside = "".join(f" in '{group.name}'" for group in reversed(self.path))
        return f"Feed({self.node.name if self.node else self.socket.node.name}: {where}{inside})"


def live_link(socket):
    """The link into an input that Blender evaluates, or None (Cycles'
    add_nodes skips invalid, muted and unavailable links)."""
    for link in socket.links:
        if link.is_valid and not link.is_muted and link.from_socket.enabled and link.to_socket.enabled:
            return link
    return None


def active_output(nodes):
    """The one of these output nodes Blender uses: the active one, else the
    first (ntreeShaderOutputNode, node_shader_tree.cc)."""
    nodes = list(nodes)
    return next((n for n in nodes if n.is_active_output), nodes[0] if nodes else None)


def counterpart(sockets, socket):
    """The socket of `sockets` that is `socket`'s counterpart across a group
    boundary: the same identifier (every Blender gives a group node's sockets
    and its Group Input / Output nodes' the interface's identifiers); by
    position if none matches."""
    for candidate in sockets:
        if candidate.identifier == socket.identifier:
            return candidate
    index = list(socket.node.outputs if socket.is_output else socket.node.inputs).index(socket)
    return sockets[index] if index < len(sockets) else None


def feed(socket, path=()):
    """The Feed of an input socket: through live links, reroutes, muted nodes,
    group nodes (into their active Group Output) and Group Input nodes (out to
    the group node of `path`, the groups `socket` sits inside, outermost first;
    a Group Input with no group node to leave to drives nothing)."""
    owner = socket  # the input whose value counts if the walk ends in nothing
    for _ in range(MAX_STEPS):
        link = live_link(socket)
        if link is None:
            return Feed(None, None, owner, path)
        node, output = link.from_node, link.from_socket
        if node.bl_idname == "NodeReroute":
            socket = node.inputs[0]
        elif node.mute:
            internal = next((l for l in node.internal_links if l.to_socket == output), None)
            if internal is None:
                return Feed(None, None, owner, path)
            socket = internal.from_socket
        elif node.bl_idname == "ShaderNodeGroup":
            inner = node.node_tree and active_output(n for n in node.node_tree.nodes
                                                     if n.bl_idname == "NodeGroupOutput")
            matched = counterpart(inner.inputs, output) if inner else None
            if matched is None:
                return Feed(None, None, owner, path)
            socket = owner = matched
            path = path + (node,)
        elif node.bl_idname == "NodeGroupInput":
            matched = counterpart(path[-1].inputs, output) if path else None
            if matched is None:
                return Feed(None, None, owner, path)
            socket = owner = matched
            path = path[:-1]
        else:
            return Feed(node, output, socket, path)
    raise NodeTreeCycle(f"the links into '{owner.node.name}' loop through node groups: break the loop")


def driver(socket, path=()):
    """The output socket that really drives an input, or None."""
    return feed(socket, path).output


def source_in_tree(socket):
    """The output socket of `socket`'s own tree whose value reaches it, for a
    link that takes its place: the driver when it is in that tree, else the
    output its live link comes from (a group node's, a reroute's), which
    carries the same value. None when nothing drives it."""
    fed = feed(socket)
    if fed.node is None:
        return None
    return fed.output if not fed.path else live_link(socket).from_socket

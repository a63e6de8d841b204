"""What differs between the Blenders Penumbra supports (Debian's 3.4, 4.2+
and 5.x), kept in one place; each check names the version that changed it
and why. Everything else about the bpy API Penumbra uses is the same."""

import bpy

# Blender 5.0 made materials and worlds node-based unconditionally:
# `Material.use_nodes` and `World.use_nodes` are deprecated (removal planned
# for 6.0), always read True, setting them does nothing and every access
# raises a DeprecationWarning (5.0 Python API release notes, "Shading":
# blender/blender PR #141278 for materials, #142342 for worlds). A new
# material or world already has its node tree.
# Path properties that take a path relative to the .blend ("//..."): 5.x
# warns when one without this option is given such a path; 4.5 has the
# option, 3.4 refuses it (its properties have no such flag).
BLEND_RELATIVE_PATH = ({"PATH_SUPPORTS_BLEND_RELATIVE"}
                       if "is_path_supports_blend_relative" in bpy.types.Property.bl_rna.properties else set())
ALWAYS_USES_NODES = bpy.app.version >= (5, 0, 0)


def uses_nodes(id_block):
    """True when a material or world is drawn by its node tree."""
    if id_block is None or id_block.node_tree is None:
        return False
    if ALWAYS_USES_NODES:
        return True
    return bool(id_block.use_nodes)


def ensure_nodes(id_block):
    """Makes a material or world use its node tree and returns the tree.
    Before 5.0 this switches Use Nodes on (which also creates the tree);
    from 5.0 there is nothing to switch."""
    if not ALWAYS_USES_NODES and not id_block.use_nodes:
        id_block.use_nodes = True
    return id_block.node_tree


def socket_is(socket, identifier):
    """Compares a node socket by its identifier, not its name: Blender 5.0
    spelled abbreviated socket names out, so the "Fac" sockets (Noise
    Texture, ColorRamp, Mix Shader, Attribute...) are named "Factor" and
    keep the identifier "Fac" (blender/blender PR #140498). Lookups such as
    node.inputs["Fac"] still work (they also match identifiers); comparing
    `socket.name` does not. Identifiers are the same in every version."""
    return socket is not None and socket.identifier == identifier

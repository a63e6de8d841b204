"""penumbra.add_surface_filter: put the height- or slope-correlated filter of
a baked colour map (paper Sec. 5.1 / 5.2; height_ramp.height_ramp_group /
slope_ramp.slope_ramp_group) in place of a "Penumbra Filtered Ramp", and
penumbra.remove_surface_filter to put the filtered ramp back.

What the operator does, on the active material's node tree:
- the filtered ramp is the active node if it is one (or the surface filter
  the active node is), else the only one in the tree;
- the new group samples the SAME lookup image with the same spec (read from
  the filtered ramp's group: its Image Texture node and "penumbra_lookup");
- Height Mean / Value at Zero Slope take what fed the filtered ramp's Mean,
  Height Sigma what fed its Sigma (the link, or the unlinked value); every
  link that left the ramp's Color and Alpha now leaves the new node; the
  height group's Visibility stays unlinked;
- the filtered ramp stays in the tree, muted and labelled, its inputs still
  linked, so remove_surface_filter (or Ctrl-Z) puts it back.

Directions (both groups take world vectors; the height group's Light
Direction points from the surface towards the light, the slope group's
Direction is projected onto the surface by the group):
- SUN (default): the +Z axis of the scene's first visible Sun lamp (by name;
  visible in the view layer and enabled for render); a sun shines along its
  local −Z, so +Z points towards it. With no such lamp the height filter
  uses straight up (+Z), the slope filter the view (see VIEW).
- VIEW: a Geometry node's Incoming (towards the camera) is linked in. For
  the height filter that is a light at the camera. For the slope filter it
  is the classic slope-correlated colour: the value follows how the facets
  face the camera (the group already narrows and shifts the slopes towards
  the viewer; Direction chooses which slope component the value reads). A
  world direction straight up would be perpendicular to a flat floor and
  give the slope filter no direction at all, hence the view as its fallback.
- CUSTOM: the operator's Direction, a constant world vector.
The direction is copied, not driven: move the sun and run the operator's
redo panel (or edit the node's input) to follow it.

Running it again: a ramp already filtered by a surface filter of the same
kind is left alone (reported, CANCELLED, nothing changed: change the node's
inputs, or use the redo panel right after adding it); a filter of the other
kind is replaced by the new one (its output links move over; links from a
height filter's Visibility are dropped and reported).

Known limits: the slope group has no input for the value's own spread, so
the noise filter's Sigma (the pixel footprint) does not reach it; the slope
filter filters the slope term only. restore_color_ramp does not know about
surface filters: run on a filtered ramp under one, it brings the ColorRamp
back unlinked and strands the filter, so the panel greys it out there
(remove the surface filter first)."""

import math
import os

import bpy

from . import height_ramp, microsurface, node_groups, slope_ramp
from .material import BakeError, Rollback, active_material, editable_material
from .. import node_links, world
from ..errors import CORE_ERRORS, describe

FILTERS = {
    # kind: (node name and label, what feeds the group from the filtered ramp, its direction input)
    "HEIGHT": ("Penumbra Height Filter", {"Height Mean": "Mean", "Height Sigma": "Sigma"}, "Light Direction"),
    "SLOPE": ("Penumbra Slope Filter", {"Value at Zero Slope": "Mean", "Value Sigma": "Sigma"}, "Direction"),
}
KIND_KEY = "penumbra_surface_filter"      # on the filter node: its kind
RAMP_KEY = "penumbra_filtered_ramp"       # on the filter node: the filtered ramp it replaces
RAMP_STATE_KEY = "penumbra_ramp_state"    # on the filter node: the ramp's label and location before
VIEW_KEY = "penumbra_view_node"           # on the filter node: its Geometry node (VIEW direction)
MUTED_LABEL = "Penumbra: filtered ramp (muted, under {})"
SPEC_KEYS = ("width", "height", "sigma_max", "mean_min", "mean_max", "sigma_spacing")


def is_filtered_ramp(node):
    """A group node of a baked "Penumbra Filtered Ramp" group."""
    group = getattr(node, "node_tree", None)
    return (node.bl_idname == "ShaderNodeGroup" and group is not None
            and group.name.startswith(node_groups.FILTERED_RAMP) and "penumbra_lookup" in group)


def filter_kind(node):
    """'HEIGHT' or 'SLOPE' for a node this operator added, else None."""
    kind = node.get(KIND_KEY) if node is not None else None
    return kind if kind in FILTERS else None


def filters_of(tree, ramp):
    """The surface-filter nodes that replaced the filtered ramp `ramp`."""
    return [n for n in tree.nodes if filter_kind(n) and n.get(RAMP_KEY) == ramp.name]


def _material_tree(context):
    material = active_material(context)
    return material.node_tree if material is not None and material.node_tree is not None else None


def panel_state(context):
    """For the panel's buttons, in the active material: (a filtered ramp
    exists, a surface filter exists, the active node is a filtered ramp under
    a surface filter). In the last case Restore ColorRamp would bring the
    ramp back unlinked and leave the filter without its inputs, so the panel
    greys it out until the filter is removed."""
    tree = _material_tree(context)
    if tree is None:
        return False, False, False
    active = tree.nodes.active
    covered = active is not None and is_filtered_ramp(active) and bool(filters_of(tree, active))
    return any(is_filtered_ramp(n) for n in tree.nodes), any(filter_kind(n) for n in tree.nodes), covered


def find_filtered_ramp(material):
    """The filtered ramp to work on: the active node (or the filtered ramp of
    the active surface filter), else the only one in the tree."""
    tree = material.node_tree
    active = tree.nodes.active
    if active is not None and is_filtered_ramp(active):
        return active
    if filter_kind(active):
        ramp = tree.nodes.get(active.get(RAMP_KEY, ""))
        if ramp is not None and is_filtered_ramp(ramp):
            return ramp
    ramps = [n for n in tree.nodes if is_filtered_ramp(n)]
    if len(ramps) == 1:
        return ramps[0]
    if not ramps:
        raise BakeError(f"'{material.name}' has no baked {node_groups.FILTERED_RAMP}: click its ColorRamp and "
                        "press Bake Filtered Ramp first (nothing was changed)")
    names = ", ".join(f"'{n.name}'" for n in ramps)
    raise BakeError(f"'{material.name}' has {len(ramps)} filtered ramps ({names}) and none is active: click the one "
                    "to filter in the Shader Editor (nothing was changed)")


def lookup_of(ramp):
    """(image, spec) of a filtered ramp: the image its group samples, and the
    lookup's layout the bake stored on the group."""
    group = ramp.node_tree
    stored = group["penumbra_lookup"]
    stored = stored.to_dict() if hasattr(stored, "to_dict") else dict(stored)
    if any(key not in stored for key in SPEC_KEYS):
        raise BakeError(f"'{ramp.name}' does not say how its lookup is laid out: bake it again")
    spec = {key: stored[key] for key in SPEC_KEYS}
    sampler = next((n for n in group.nodes if n.bl_idname == "ShaderNodeTexImage"), None)
    image = sampler.image if sampler is not None else None
    if image is None:
        raise BakeError(f"The lookup image of '{ramp.name}' ('{stored.get('image', '?')}') was removed: bake the "
                        "ramp again, or point the group's Image Texture at the lookup (nothing was changed)")
    width, height = image.size
    if width < 1 or height < 1:
        raise BakeError(f"The lookup image '{image.name}' of '{ramp.name}' has no pixels: {world.unreadable(image)}; "
                        "or bake the ramp again (nothing was changed)")
    return image, spec


def sun_direction(scene):
    """(direction towards the light, lamp name) of the first visible Sun lamp
    by name, or (None, None). A sun shines along its local −Z."""
    suns = sorted((o for o in scene.objects if o.type == "LIGHT" and o.data.type == "SUN"
                   and o.visible_get() and not o.hide_render), key=lambda o: o.name)
    if not suns:
        return None, None
    axis = suns[0].matrix_world.to_3x3().col[2]
    if axis.length < 1e-12:
        return None, None
    return tuple(axis.normalized()), suns[0].name


def _lookup_folder(image):
    """The folder of the lookup's file (so the microsurface table saved with
    the .blend sits beside it, not in the session's temporary folder)."""
    if image.packed_file is None and image.filepath:
        return os.path.dirname(bpy.path.abspath(image.filepath, library=image.library))
    return None


def _move_output_links(tree, source, target, names=("Color", "Alpha")):
    """Every link that leaves source's outputs `names` leaves target's instead."""
    for name in names:
        for socket in [link.to_socket for link in source.outputs[name].links]:
            tree.links.new(target.outputs[name], socket)  # a new link into an input replaces the old one


def _feed(tree, ramp, socket, ramp_input):
    """socket takes what fed the filtered ramp's input: what drives it (never
    a muted link; node_links.py), or its value."""
    source = node_links.source_in_tree(ramp.inputs[ramp_input])
    if source is not None:
        tree.links.new(source, socket)
    else:
        socket.default_value = ramp.inputs[ramp_input].default_value


def _remove_filter_node(tree, node):
    view = tree.nodes.get(node.get(VIEW_KEY, ""))
    tree.nodes.remove(node)
    if view is not None and not any(o.is_linked for o in view.outputs):
        tree.nodes.remove(view)


def _direction_input(op, context, tree, node, kind):
    """Sets or links the filter's direction input; returns what was used, for the report."""
    socket = node.inputs[FILTERS[kind][2]]
    source = op.direction_source
    if source == "SUN":
        direction, sun = sun_direction(context.scene)
        if direction is not None:
            socket.default_value = direction
            op.direction = direction  # the redo panel shows it, and Custom starts from it
            return f"towards Sun lamp '{sun}' ({direction[0]:.3f}, {direction[1]:.3f}, {direction[2]:.3f})"
        if kind == "HEIGHT":
            socket.default_value = (0.0, 0.0, 1.0)
            return "straight up (no visible Sun lamp)"
        source = "VIEW"
    if source == "VIEW":
        geometry = tree.nodes.new("ShaderNodeNewGeometry")
        geometry.name = geometry.label = f"{node.name} View"
        geometry.location = (node.location.x - 200, node.location.y - 260)
        tree.links.new(geometry.outputs["Incoming"], socket)
        node[VIEW_KEY] = geometry.name
        what = "the view (Geometry Incoming)"
        return what if op.direction_source == "VIEW" else f"{what}, no visible Sun lamp"
    socket.default_value = tuple(op.direction)
    d = op.direction
    return f"custom ({d[0]:.3f}, {d[1]:.3f}, {d[2]:.3f})"


def _add_filter(op, context, tree, ramp, replaced):
    """Builds the filter node in place of `ramp` (or of `replaced`, a filter
    of the other kind, which goes). Returns (node, direction used)."""
    kind = op.kind
    name, feeds, _ = FILTERS[kind]
    image, spec = lookup_of(ramp)
    # The groups read the microsurface table by name; written beside the
    # lookup (not in the session's temporary folder) it survives a reload.
    microsurface.microsurface_image(_lookup_folder(image))
    build = height_ramp.height_ramp_group if kind == "HEIGHT" else slope_ramp.slope_ramp_group
    group = build(image, spec)
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    node.name = node.label = name
    node[KIND_KEY] = kind
    node[RAMP_KEY] = ramp.name
    front = replaced if replaced is not None else ramp
    node.location = front.location
    for group_input, ramp_input in feeds.items():
        _feed(tree, ramp, node.inputs[group_input], ramp_input)
    node.inputs["Slope Sigma"].default_value = op.slope_sigma
    if kind == "SLOPE":
        node.inputs["Value per Slope"].default_value = op.value_per_slope
    used = _direction_input(op, context, tree, node, kind)
    _move_output_links(tree, front, node)
    if replaced is not None:
        node[RAMP_STATE_KEY] = replaced[RAMP_STATE_KEY]
        _remove_filter_node(tree, replaced)
    else:
        node[RAMP_STATE_KEY] = {"label": ramp.label, "location": tuple(ramp.location)}
        ramp.location = (ramp.location.x, ramp.location.y - 600)
    ramp.mute = True
    ramp.label = MUTED_LABEL.format(node.name)
    tree.nodes.active = node
    return node, used


_DIRECTION_SOURCES = [
    ("SUN", "Sun Lamp", "Towards the scene's first visible Sun lamp (by name); without one, straight up for the "
                        "height filter and the view for the slope filter"),
    ("VIEW", "View", "Towards the camera (a Geometry node's Incoming): a light at the camera for the height "
                     "filter, the slope facing the camera for the slope filter"),
    ("CUSTOM", "Custom", "The Direction below, a world vector"),
]


class PENUMBRA_OT_add_surface_filter(bpy.types.Operator):
    """Filter the baked colour map over the surface's micro-heights (lit and seen) or micro-slopes (seen):
replaces the Penumbra Filtered Ramp's output by the height or slope group on the same lookup"""
    bl_idname = "penumbra.add_surface_filter"
    bl_label = "Add Surface Filter"
    bl_options = {"REGISTER", "UNDO"}

    kind: bpy.props.EnumProperty(
        name="Filter", default="HEIGHT",
        items=[("HEIGHT", "Height", "Colour correlated to the micro-heights: only the visible and lit heights "
                                    "count (paper Sec. 5.1)"),
               ("SLOPE", "Slope", "Colour correlated to the micro-slopes: only the facets the camera sees count "
                                  "(paper Sec. 5.2)")])
    slope_sigma: bpy.props.FloatProperty(
        name="Slope Sigma", default=0.2, min=0.0, soft_max=1.0, max=100.0, precision=3,
        description="Standard deviation of the microsurface's slopes (0: flat, the plain filtered ramp)")
    value_per_slope: bpy.props.FloatProperty(
        name="Value per Slope", default=1.0, soft_min=-10.0, soft_max=10.0,
        description="Slope filter: how much the ramp's input changes per unit of slope along the direction")
    direction_source: bpy.props.EnumProperty(name="Direction", items=_DIRECTION_SOURCES, default="SUN")
    direction: bpy.props.FloatVectorProperty(
        name="Custom Direction", size=3, subtype="DIRECTION", default=(0.0, 0.0, 1.0),
        description="World direction used with Custom: towards the light (height), the slope's axis (slope)")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(self, "kind")
        layout.prop(self, "slope_sigma")
        if self.kind == "SLOPE":
            layout.prop(self, "value_per_slope")
        layout.prop(self, "direction_source")
        if self.direction_source == "CUSTOM":
            layout.prop(self, "direction")

    def execute(self, context):
        try:
            material = editable_material(context)
            tree = material.node_tree
            ramp = find_filtered_ramp(material)
            existing = filters_of(tree, ramp)
            same = [n for n in existing if filter_kind(n) == self.kind]
            if same:
                self.report({"INFO"}, f"'{ramp.name}' is already filtered by '{same[0].name}': change its inputs "
                                      "there, or remove it first (nothing was changed)")
                return {"CANCELLED"}
            if self.direction_source == "CUSTOM" and math.fsum(v * v for v in self.direction) < 1e-24:
                raise BakeError("The custom direction is zero: give it a length (nothing was changed)")
            lookup_of(ramp)  # every check before any change
            replaced = existing[0] if existing else None
            replaced_name = replaced.name if replaced is not None else ""
            dropped = sum(len(s.links) for s in replaced.outputs if s.name not in ("Color", "Alpha")) \
                if replaced is not None else 0
            rollback = Rollback(tree, ramp)
            try:
                node, used = _add_filter(self, context, tree, ramp, replaced)
            except BaseException:
                rollback.restore()
                raise
        except (BakeError, *CORE_ERRORS) as error:
            self.report({"ERROR"}, describe(error))
            return {"CANCELLED"}
        what = "Height" if self.kind == "HEIGHT" else "Slope"
        message = f"{what} filter '{node.name}' now filters '{ramp.name}' in '{material.name}'; direction: {used}"
        if replaced is not None:
            message += f"; it replaces '{replaced_name}'"
            if dropped:
                message += f" ({dropped} link(s) from its Visibility were dropped)"
        self.report({"INFO"}, message)
        return {"FINISHED"}


class PENUMBRA_OT_remove_surface_filter(bpy.types.Operator):
    """Remove the active height or slope filter and put its Penumbra Filtered Ramp back"""
    bl_idname = "penumbra.remove_surface_filter"
    bl_label = "Remove Surface Filter"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            material = editable_material(context)
            tree = material.node_tree
            node = self._filter_node(material)
            ramp = tree.nodes.get(node.get(RAMP_KEY, ""))
            if ramp is None or not is_filtered_ramp(ramp):
                raise BakeError(f"The filtered ramp '{node.get(RAMP_KEY, '?')}' of '{node.name}' was deleted or "
                                "renamed: undo that change, or delete the filter by hand (nothing was changed)")
        except BakeError as error:
            self.report({"ERROR"}, describe(error))
            return {"CANCELLED"}
        _move_output_links(tree, node, ramp)
        state = node.get(RAMP_STATE_KEY)
        ramp.mute = False
        ramp.label = state["label"] if state is not None else ""
        if state is not None:
            ramp.location = tuple(state["location"])
        name = node.name
        _remove_filter_node(tree, node)
        tree.nodes.active = ramp
        self.report({"INFO"}, f"Removed '{name}': '{ramp.name}' filters '{material.name}' again")
        return {"FINISHED"}

    @staticmethod
    def _filter_node(material):
        """The active surface filter (or the one that replaced the active
        filtered ramp), else the only one in the tree."""
        tree = material.node_tree
        active = tree.nodes.active
        if filter_kind(active):
            return active
        candidates = filters_of(tree, active) if active is not None and is_filtered_ramp(active) else \
            [n for n in tree.nodes if filter_kind(n)]
        if len(candidates) == 1:
            return candidates[0]
        if not candidates:
            raise BakeError(f"'{material.name}' has no Penumbra height or slope filter to remove (nothing was "
                            "changed)")
        raise BakeError(f"'{material.name}' has {len(candidates)} surface filters and none is active: click the one "
                        "to remove in the Shader Editor (nothing was changed)")


classes = (PENUMBRA_OT_add_surface_filter, PENUMBRA_OT_remove_surface_filter)

"""How the Noise Filter follows the render: a driver on its Samples input
that reads the scene's render samples of the engine it renders with
(docs/colormap.md, "Sample-count-aware filter"), and, for a noise too costly
for EEVEE at 16 taps, the smaller group the bake made for EEVEE, swapped in
when a render starts with EEVEE and out again with Cycles.

A single-property driver needs no Python at render time, so the .blend
renders the same on a farm without the add-on or with scripts disabled. A
driver can't choose between engines by itself (render.engine is a string),
so the bake points it at the scene's engine and a render_init handler
re-points it when the engine was changed since."""

import bpy
from bpy.app.handlers import persistent

NOISE_FILTER_PREFIX = "Penumbra Noise Filter"
# Custom properties of a Noise Filter node whose noise EEVEE gets fewer taps
# for (noise_maths.tap_count): the group each engine renders with.
GROUP_FOR_CYCLES = "penumbra_group_cycles"
GROUP_FOR_EEVEE = "penumbra_group_eevee"
# A one-evaluation Noise Filter (filter_quality presets with one tap) keeps
# the group with the 16 taps for one sample and the group without them for
# more: the latter renders the same numbers above one sample without the
# taps' thousand nodes, which Cycles syncs and folds at every render
# (docs/colormap.md, "One evaluation per sample").
GROUP_AT_ONE_SAMPLE = "penumbra_group_one_sample"
GROUP_ABOVE_ONE_SAMPLE = "penumbra_group_samples"


def remember_group(node, key, group):
    """Keeps `group` on `node` under `key` by name, with a fake user so the
    .blend keeps it while no node uses it. Not as a pointer: a node's ID
    property that points at a node tree makes the render's depsgraph copy
    that tree at every render (measured: the 16-tap groups added 0.025 CPU s
    to each render of the 96×54 benchmark plane, as much as 8 plain spp)."""
    group.use_fake_user = True
    node[key] = group.name


def remembered_group(node, key):
    """The group remember_group kept (or, in files baked before, the group
    the property points at), or None."""
    value = node.get(key)
    if isinstance(value, str):
        value = bpy.data.node_groups.get(value)
    return value if isinstance(value, bpy.types.ShaderNodeTree) else None
EEVEE_ENGINES = ("BLENDER_EEVEE", "BLENDER_EEVEE_NEXT")

# Render sample count per engine: the same RNA paths in 3.4, 4.x and 5.x
# (EEVEE Next in 4.2+ kept taa_render_samples).
_SAMPLES_PATH = {"CYCLES": "cycles.samples", "BLENDER_EEVEE": "eevee.taa_render_samples",
                 "BLENDER_EEVEE_NEXT": "eevee.taa_render_samples"}


def samples_path(scene):
    """The scene's render-sample property for its engine, or None (Workbench
    and other engines: the filter is told one sample)."""
    return _SAMPLES_PATH.get(scene.render.engine)


def render_samples(scene):
    path = samples_path(scene)
    return float(scene.path_resolve(path)) if path else 1.0


def drive_samples(node, scene):
    """Adds (or re-points) the driver of `node`'s Samples input."""
    socket = node.inputs["Samples"]
    socket.default_value = render_samples(scene)
    path = samples_path(scene)
    tree = node.id_data
    data_path = socket.path_from_id("default_value")
    curve = tree.animation_data.drivers.find(data_path) if tree.animation_data else None
    if path is None:
        if curve is not None:
            tree.animation_data.drivers.remove(curve)
        return
    if curve is None:
        curve = socket.driver_add("default_value")
    driver = curve.driver
    driver.type = "AVERAGE"
    variable = driver.variables[0] if len(driver.variables) else driver.variables.new()
    variable.name = "samples"
    variable.type = "SINGLE_PROP"
    target = variable.targets[0]
    target.id_type = "SCENE"
    target.id = scene
    target.data_path = path


def remove_driver(node):
    """Removes the Samples driver of a node about to be deleted (a driver
    whose node is gone would stay in the tree as an error)."""
    tree = node.id_data
    if "Samples" not in node.inputs or tree.animation_data is None:
        return
    curve = tree.animation_data.drivers.find(node.inputs["Samples"].path_from_id("default_value"))
    if curve is not None:
        tree.animation_data.drivers.remove(curve)


def noise_filter_nodes(material):
    tree = material.node_tree
    if tree is None:
        return []
    return [n for n in tree.nodes if n.bl_idname == "ShaderNodeGroup" and n.name.startswith(NOISE_FILTER_PREFIX)
            and "Samples" in n.inputs]


def sample_count_ramps(material):
    """Filtered Ramp nodes with a group per sample count (one-evaluation
    presets): they follow the render's samples as their Noise Filter does."""
    tree = material.node_tree
    if tree is None:
        return []
    return [n for n in tree.nodes if n.bl_idname == "ShaderNodeGroup" and GROUP_ABOVE_ONE_SAMPLE in n
            and not n.name.startswith(NOISE_FILTER_PREFIX)]


def fit_group(node, scene):
    """Gives `node` the group baked for `scene`'s engine, where the bake made
    one per engine, and for its sample count, where it made one without
    taps; returns whether it changed."""
    key = GROUP_FOR_EEVEE if scene.render.engine in EEVEE_ENGINES else GROUP_FOR_CYCLES
    group = remembered_group(node, key) or remembered_group(node, GROUP_AT_ONE_SAMPLE)
    if render_samples(scene) > 1.0 and remembered_group(node, GROUP_ABOVE_ONE_SAMPLE) is not None:
        group = remembered_group(node, GROUP_ABOVE_ONE_SAMPLE)
    if group is None or node.node_tree == group:
        return False
    node.node_tree = group
    return True


def retarget(scene):
    """Points every Noise Filter's driver at `scene`'s engine and gives it
    the engine's group (fit_group); returns how many nodes were changed."""
    path = samples_path(scene)
    changed = 0
    for material in bpy.data.materials:
        if material.library is not None:
            continue
        for node in sample_count_ramps(material):
            changed += fit_group(node, scene)
        for node in noise_filter_nodes(material):
            swapped = fit_group(node, scene)
            tree = node.id_data
            data_path = node.inputs["Samples"].path_from_id("default_value")
            curve = tree.animation_data.drivers.find(data_path) if tree.animation_data else None
            current = curve.driver.variables[0].targets[0] if curve and len(curve.driver.variables) else None
            repointed = current is None or current.data_path != path or current.id != scene
            if repointed:
                drive_samples(node, scene)
            changed += swapped or repointed
    return changed


@persistent
def on_render_init(scene, *_args):
    retarget(scene)


def register():
    if on_render_init not in bpy.app.handlers.render_init:
        bpy.app.handlers.render_init.append(on_render_init)


def unregister():
    if on_render_init in bpy.app.handlers.render_init:
        bpy.app.handlers.render_init.remove(on_render_init)

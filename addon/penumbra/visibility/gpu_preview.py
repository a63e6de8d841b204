"""GPU viewport preview of the visibility shading: paper §4.3 steps 2–5
(lobes → SH → 1D-BRDF operator → dot with the lighting) in a GLSL vertex
shader (preview_shader.py), drawn over every enabled object in the 3D
viewport and following the pose. A display mode only
(`scene.penumbra.visibility.gpu_preview`): the `penumbra_shading` /
`penumbra_visibility` attributes, the CPU run time and renders are
untouched by it.

What the viewport draws (gpu_model.py): the model itself lives on the GPU,
uploaded once (its stored binary16 blocks, scales, joint directions and
per-vertex layout, as textures), and the vertex shader evaluates §4.3 step 1
(the linear model, the lobes) and the vertex frame before steps 2–5. Per
frame the CPU reads the pose's joint features (the core, a few microseconds),
the evaluated mesh's positions, the lighting and the camera (frame_of); the
draw callback uploads them (one texture, two uniform blocks) and draws; the
shader takes the normals from the positions by Blender's rule. Neither ever
raises into Blender: problems go to the scene's `gpu_preview_status`.

object_inputs / inputs_from_arrays / DrawBatch / shade_offscreen are the
earlier path (the CPU's lobes and frames as vertex attributes), kept as the
check of steps 2–5 alone against `_penumbra.sh.shade_pose`.

It matches the CPU shading to float rounding (shade_offscreen reads it back
from an RGBA32F buffer, one vertex per pixel; tests/blender/visibility/test_gpu_preview.py
compares it under Xvfb and in the bpy 5.x module after gpu.init()).

Limits: SH orders 1–8 and 1–4 lobes (everything a visibility model can
hold). The viewport colour is the scene-linear shade with the sRGB curve,
not the scene's view transform. Phong's viewer is the scene camera, as for
the attributes, not the viewport's eye.

No GPU (the bpy module or `blender -b`): the setting can still be switched
on; gpu_preview_status then says why nothing is drawn.
"""

import time

import bpy
import numpy as np
from bpy.app.handlers import persistent

from .. import native
from . import enabled_objects, frame_shading, gpu_model, mesh_data, model_shader, preview_shader, world_lighting
from .preview_shader import MAX_LOBES, MAX_ORDER, MODELS, check_configuration, lobe_vec4_count  # noqa: F401
from .input_error import VisibilityInputError

READBACK_WIDTH = 1024  # pixels per row when shading into an offscreen buffer, one vertex per pixel
# Pulls the preview's triangles towards the eye by this fraction of clip w, so
# they win the depth test against Blender's own drawing of the same surface.
DEPTH_BIAS = 2e-5


class PoseInputs:
    """Everything one draw of one object needs, computed on the CPU: vertex
    attributes (pack_vertex_data), triangles, the uniform block's bytes and
    the configuration (order, lobes, model)."""

    def __init__(self, order, lobes, model, attributes, triangles, uniforms):
        check_configuration(order, lobes, model)
        self.order, self.lobes, self.model = order, lobes, model
        self.attributes = attributes
        self.triangles = triangles
        self.uniforms = uniforms
        self.vertex_count = len(attributes["p_position"])
        self.seconds = {}


def inputs_from_arrays(order, lighting, axes, bands, normals, tangents, positions=None, model="diffuse",
                       phong_exponent=16.0, camera=(0.0, 0.0, 0.0), transmission=(0.5, 0.5, 0.5),
                       triangles=None):
    """PoseInputs from the arrays `_penumbra.sh.shade_pose` takes (same meaning)."""
    axes = np.asarray(axes, dtype=np.float32)
    bands = np.asarray(bands, dtype=np.float32)
    if positions is None:
        positions = np.zeros((len(axes), 3), dtype=np.float32)
    attributes = preview_shader.pack_vertex_data(positions, normals, tangents, axes, bands)
    uniforms = preview_shader.uniform_data(order, lighting, model, phong_exponent, camera, transmission)
    tri = np.zeros((0, 3), dtype=np.int32) if triangles is None else np.asarray(triangles, dtype=np.int32)
    return PoseInputs(order, axes.shape[1], model, attributes, tri, uniforms)


_mesh_buffers = {}  # object name -> mesh_data.MeshBuffers (the preview's own: the CPU run time reuses its)


def object_inputs(obj, scene, depsgraph=None):
    """PoseInputs of an enabled object at the scene's current state: the same
    model, mesh, frames, lighting and BRDF as frame_shading.shade_object.
    Raises VisibilityInputError / ValueError / OSError like it."""
    t0 = time.perf_counter()
    core = native.require()
    entry = frame_shading.loaded_model(obj)
    model = entry.model
    settings = obj.penumbra_visibility
    brdf = settings.brdf.lower()
    check_configuration(model.order, model.lobes, brdf)
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    rotations = frame_shading.posed_rotations(obj, model, depsgraph)
    buffers = _mesh_buffers.get(obj.name)
    if buffers is None or buffers.vertex_count != model.vertex_count:
        buffers = _mesh_buffers[obj.name] = mesh_data.MeshBuffers(obj.data)
    frame = mesh_data.evaluated_mesh(obj, depsgraph, with_topology=False, buffers=buffers)
    if len(frame.positions) != model.vertex_count:
        raise VisibilityInputError(f"'{obj.name}' has {len(frame.positions)} vertices after its modifiers; "
                                   f"the model has {model.vertex_count}")
    t1 = time.perf_counter()
    threads = scene.penumbra.visibility.threads
    axes, bands, _ = model.synthesize(rotations, threads)
    t2 = time.perf_counter()
    frames, _ = core.visibility.vertex_frames(frame.positions, frame.normals, entry.buffers.triangles,
                                              entry.neighbours)
    t3 = time.perf_counter()
    lighting, _ = world_lighting.world_lighting(scene, model.order)
    camera = np.array(scene.camera.matrix_world.translation) if scene.camera else np.zeros(3)
    inputs = inputs_from_arrays(model.order, lighting, axes, bands, frames[:, 2], frames[:, 0],
                                positions=frame.positions, model=brdf, phong_exponent=settings.phong_exponent,
                                camera=camera, transmission=np.array(settings.transmission[:]),
                                triangles=entry.buffers.triangles)
    t4 = time.perf_counter()
    inputs.seconds = {"read": t1 - t0, "pose_to_lobes": t2 - t1, "frames": t3 - t2, "pack": t4 - t3,
                      "cpu_total": t4 - t0}
    return inputs


# The GPU side ---------------------------------------------------------------------

_gpu_found = False  # a backend once found stays for the session: not asked again every frame


def gpu_unavailable_reason():
    """None when Blender's gpu module can draw here; else why not, in a sentence."""
    global _gpu_found
    if _gpu_found:
        return None
    try:
        import gpu
    except ImportError as error:
        return f"no GPU available: the gpu module cannot load ({error})"
    if bpy.app.background and bpy.app.version < (4, 0, 0):
        # Blender 3.x has no GPU context in background mode, and its gpu
        # calls crash there instead of raising: nothing is asked.
        return "no GPU available: Blender runs in background mode (blender -b)"
    try:
        backend = gpu.platform.backend_type_get()
    except (SystemError, RuntimeError) as error:
        # 4.x/5.x in background: "GPU functions for drawing are not available
        # in background mode" (5.x: until gpu.init() is called).
        return f"no GPU available: {error}"
    if backend == "NONE":
        return "no GPU available: Blender has no GPU backend here"
    _gpu_found = True
    return None


_shaders = {}  # (order, lobes, model, readback) -> GPUShader


def shader_for(order, lobes, model, readback):
    """The compiled shader of one configuration (cached)."""
    key = (order, lobes, model, readback)
    shader = _shaders.get(key)
    if shader is not None:
        return shader
    info = gpu_model.shader_info(order)
    slot = 0
    for name in ("p_position", "p_normal", "p_tangent"):
        info.vertex_in(slot, "VEC3", name)
        slot += 1
    for k in range(lobe_vec4_count(order, lobes)):
        info.vertex_in(slot, "VEC4", f"p_lobe{k}")
        slot += 1
    info.typedef_source(preview_shader.uniform_block_source(order))
    info.uniform_buf(0, "PenumbraShading", "shading")
    shader = gpu_model.finish_shader(info, readback, preview_shader.vertex_source(order, lobes, model, readback),
                                     "penumbra_preview")
    _shaders[key] = shader
    return shader


def _vertex_buffer(inputs):
    import gpu
    fmt = gpu.types.GPUVertFormat()
    names = ["p_position", "p_normal", "p_tangent"] + [f"p_lobe{k}" for k in
                                                        range(lobe_vec4_count(inputs.order, inputs.lobes))]
    for name in names:
        fmt.attr_add(id=name, comp_type="F32", len=inputs.attributes[name].shape[1], fetch_mode="FLOAT")
    vbo = gpu.types.GPUVertBuf(fmt, inputs.vertex_count)
    for name in names:
        vbo.attr_fill(name, inputs.attributes[name])
    return vbo


def shade_offscreen(inputs):
    """Shades every vertex of `inputs` on the GPU, one vertex per pixel of an
    RGBA32F offscreen buffer, and reads it back: (rgb (V, 3), visibility (V,))
    float32, unclamped (what `_penumbra.sh.shade_pose` returns). Needs a GPU
    (gpu_unavailable_reason() is None) and a GPU context: under a window
    (e.g. xvfb-run), or after gpu.init() in the bpy 5.x module."""
    import gpu
    ubo = gpu.types.GPUUniformBuf(inputs.uniforms)
    shader = shader_for(inputs.order, inputs.lobes, inputs.model, True)
    return gpu_model.read_back(shader, _vertex_buffer(inputs), inputs.vertex_count,
                               lambda bound: bound.uniform_block("shading", ubo), READBACK_WIDTH)


class DrawBatch:
    """The GPU objects of one pose of one object, for the viewport."""

    def __init__(self, inputs):
        import gpu
        self.shader = shader_for(inputs.order, inputs.lobes, inputs.model, False)
        indices = gpu.types.GPUIndexBuf(type="TRIS", seq=np.ascontiguousarray(inputs.triangles, dtype=np.int32))
        self.batch = gpu.types.GPUBatch(type="TRIS", buf=_vertex_buffer(inputs), elem=indices)
        self.ubo = gpu.types.GPUUniformBuf(inputs.uniforms)

    def draw(self, view_projection):
        import gpu
        self.shader.bind()
        self.shader.uniform_block("shading", self.ubo)
        self.shader.uniform_float("ViewProjectionMatrix", view_projection)
        self.shader.uniform_float("depth_bias", DEPTH_BIAS)
        self.batch.draw(self.shader)


# Blender integration: settings, handlers, the draw callback ---------------------

class _Preview:
    """One object's preview: its model on the GPU (made in the draw callback,
    remade when frame_shading loads another model for it) and the frame
    waiting to be uploaded."""

    def __init__(self):
        self.entry = None    # frame_shading's loaded model the GPU copy is of
        self.frame = None    # gpu_model.FrameInputs waiting to be uploaded
        self.batch = None    # gpu_model.ModelOnGpu being drawn


_previews = {}        # object name -> _Preview
_draw_handle = None
last_timings = {}     # seconds of the last update and upload (read by benchmarks)
last_drawn = []       # the objects the last draw callback drew (read by tests)
_uniform_cache = {}   # the shading block's bytes of the last inputs, per object


def _set_status(scene, message):
    settings = scene.penumbra.visibility
    if settings.gpu_preview_status != message:
        settings.gpu_preview_status = message
        if message:
            print(f"penumbra: GPU preview: {message}")


def _shading_bytes(obj, scene, order, brdf, settings):
    """The shading uniform block, rebuilt only when its inputs changed (the
    operator blocks cost more than the rest of a frame's CPU work). The
    lighting is compared by identity: lighting_until_edited gives the same
    array until the World is read again."""
    lighting = world_lighting.lighting_until_edited(scene, order)
    camera = tuple(scene.camera.matrix_world.translation) if scene.camera else (0.0, 0.0, 0.0)
    key = (order, brdf, settings.phong_exponent, camera, tuple(settings.transmission[:]))
    cached = _uniform_cache.get(obj.name)
    if cached is None or cached[0] != key or cached[1] is not lighting:
        cached = (key, lighting, preview_shader.uniform_data(order, lighting, brdf, settings.phong_exponent, camera,
                                                             np.array(settings.transmission[:])))
        _uniform_cache[obj.name] = cached
    return cached[2]


_geometry_grids = {}  # object name -> (loaded model, model_shader.GeometryGrid): the frame texture's array


def frame_of(obj, scene, depsgraph=None):
    """(frame_shading's loaded model, gpu_model.FrameInputs) of an enabled
    object at the scene's current state: the model, pose, evaluated mesh,
    lighting and BRDF frame_shading.shade_object uses. Raises
    VisibilityInputError / ValueError / OSError like it."""
    import gpu
    stamps = [time.perf_counter()]
    entry = frame_shading.loaded_model(obj)
    model = entry.model
    settings = obj.penumbra_visibility
    brdf = settings.brdf.lower()
    check_configuration(model.order, model.lobes, brdf)
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    features = model.pose_features(frame_shading.posed_rotations(obj, model, depsgraph))
    stamps.append(time.perf_counter())
    grid = _geometry_grids.get(obj.name)
    if grid is None or grid[0] is not entry:
        max_size = gpu.capabilities.max_texture_size_get()
        grid = _geometry_grids[obj.name] = (entry, model_shader.GeometryGrid(
            model.vertex_count, model_shader.texture_width(max_size), max_size))
    world = frame_shading._read_positions(obj, depsgraph, entry, out=grid[1].positions)
    stamps.append(time.perf_counter())
    frame = gpu_model.FrameInputs((grid[1].size, grid[1].flat), model_shader.pose_data(
        features, model_shader.feature_vec4_count(len(features)), world),
        _shading_bytes(obj, scene, model.order, brdf, settings), brdf)
    stamps.append(time.perf_counter())
    frame.seconds = {"pose_features": stamps[1] - stamps[0], "read_positions": stamps[2] - stamps[1],
                     "pack": stamps[3] - stamps[2], "cpu_total": stamps[3] - stamps[0]}
    return entry, frame


def _forget_absent(scene):
    """Drops what the preview holds for objects no longer enabled in the scene."""
    enabled = {obj.name for obj in enabled_objects.in_scene(scene)} if scene is not None else set()
    for name in [n for n in _previews if n not in enabled]:
        del _previews[name]
        _uniform_cache.pop(name, None)
        _geometry_grids.pop(name, None)


def update(scene, depsgraph=None):
    """Recomputes the preview's per-frame inputs of every enabled object (the
    CPU part); the next viewport draw uploads them. Never raises: problems
    go to the scene's gpu_preview_status."""
    global last_timings
    try:
        settings = scene.penumbra.visibility
        if not settings.gpu_preview:
            return
        if native.module is None:
            _set_status(scene, f"the compiled core did not load: {native.load_error}")
            return
        reason = gpu_unavailable_reason()
        if reason:
            _set_status(scene, reason)
            return
        seen, problems = set(), []
        for obj in enabled_objects.in_scene(scene):
            seen.add(obj.name)
            try:
                entry, frame = frame_of(obj, scene, depsgraph)
            except (VisibilityInputError, ValueError, RuntimeError, OSError) as error:
                problems.append(f"{obj.name}: {error}")
                _previews.pop(obj.name, None)
                continue
            preview = _previews.setdefault(obj.name, _Preview())
            if preview.entry is not entry:  # another model (or a reloaded one): its GPU copy goes
                preview.entry, preview.batch = entry, None
            preview.frame = frame
            last_timings = dict(frame.seconds)
        _forget_absent(scene)
        if not seen:
            problems.append("no object has Shade from Model on")
        _set_status(scene, "; ".join(problems))
    except Exception as error:  # a handler must never raise into Blender
        try:
            _set_status(scene, f"update failed: {error}")
        except Exception:
            pass


def _tag_redraw():
    wm = getattr(bpy.context, "window_manager", None)
    for window in (wm.windows if wm else ()):
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


def toggled(scene):
    """gpu_preview switched: report the GPU's absence, or compute the preview now."""
    world_lighting.forget_reads()  # while off, frame changes were not checked for a relit World
    if not scene.penumbra.visibility.gpu_preview:
        _previews.clear()
        _uniform_cache.clear()
        _geometry_grids.clear()
        _set_status(scene, "")
    else:
        reason = gpu_unavailable_reason()
        if reason:
            _previews.clear()
            _set_status(scene, reason)
        else:
            update(scene)
    _tag_redraw()


def request_refresh():
    """Object settings changed in the UI (BRDF, exponent, ...): recompute."""
    scene = bpy.context.scene if bpy.context else None
    if scene is not None and scene.penumbra.visibility.gpu_preview:
        world_lighting.forget_reads()
        update(scene)
        _tag_redraw()


def _draw():
    """SpaceView3D POST_VIEW callback: upload what changed, draw. Never raises."""
    if not _previews:
        return
    scene = bpy.context.scene
    try:
        if not scene.penumbra.visibility.gpu_preview:
            return
        import gpu
        view_projection = bpy.context.region_data.perspective_matrix
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(True)
        gpu.state.blend_set("NONE")
        last_drawn.clear()
        for name, preview in list(_previews.items()):
            obj = scene.objects.get(name)
            if obj is None or not obj.penumbra_visibility.enabled or not obj.visible_get():
                continue
            t0 = time.perf_counter()
            if preview.batch is None and preview.entry is not None and preview.frame is not None:
                entry = preview.entry
                preview.batch = gpu_model.ModelOnGpu(entry.model, entry.neighbours, mesh_data.polygon_topology(obj.data),
                                                     entry.buffers.triangles)
                last_timings["model_upload"] = time.perf_counter() - t0
                t0 = time.perf_counter()
            if preview.frame is not None and preview.batch is not None:
                preview.batch.set_frame(preview.frame)
                preview.frame = None
                last_timings["upload"] = time.perf_counter() - t0
            if preview.batch is not None and preview.batch.geometry is not None:
                preview.batch.draw(view_projection, DEPTH_BIAS)
                last_drawn.append(name)
        gpu.state.depth_mask_set(False)
        gpu.state.depth_test_set("NONE")
    except Exception as error:  # never raise inside Blender's draw loop
        _previews.clear()
        try:
            _set_status(scene, f"drawing failed: {error}")
        except Exception:
            pass


def _updated(depsgraph, kinds):
    kinds = tuple(getattr(bpy.types, name) for name in kinds)
    return any(isinstance(u.id, kinds) for u in depsgraph.updates)


def _armature_or_camera_changed(scene, depsgraph):
    camera = any(isinstance(u.id, bpy.types.Object) and u.id.type == "CAMERA" for u in depsgraph.updates)
    return camera or frame_shading._drives_enabled_object(scene, depsgraph.updates)


# frame_shading._busy: a bake is posing the scene frame by frame (frame_shading.paused),
# or the CPU run time is writing its attributes.
@persistent
def on_frame_change(scene, depsgraph=None):
    if scene.penumbra.visibility.gpu_preview and not frame_shading._busy:
        if depsgraph is None or any(depsgraph.id_type_updated(kind) for kind in world_lighting.RELIGHTING_ID_TYPES):
            world_lighting.forget_reads()
        update(scene, depsgraph)


@persistent
def on_depsgraph_update(scene, depsgraph):
    if _previews:  # an object deleted or switched off holds nothing on the GPU
        _forget_absent(scene)
    relit = _updated(depsgraph, world_lighting.EDITS_THAT_RELIGHT)
    if relit:
        world_lighting.forget_reads()
    else:
        # Not every Scene update relights: the timeline's cursor and the preview's own status are scene properties.
        relit = _updated(depsgraph, ("Scene",)) and world_lighting.the_scene_changed(scene)
    if scene.penumbra.visibility.gpu_preview and not frame_shading._busy and (
            relit or _armature_or_camera_changed(scene, depsgraph)):
        update(scene, depsgraph)


@persistent
def on_undo(scene, *_args):
    """An undo or redo replaced every ID: the models are looked up afresh."""
    _previews.clear()
    _uniform_cache.clear()
    _geometry_grids.clear()
    world_lighting.forget_reads()
    enabled_objects.forget()  # an undo may switch an object back on, which no callback reports
    if scene is not None and scene.penumbra.visibility.gpu_preview:
        update(scene)


@persistent
def on_load(*_args):
    """A file was opened: forget the last file's objects; a file saved with the
    preview on shows it at once."""
    _previews.clear()
    _mesh_buffers.clear()
    _uniform_cache.clear()
    _geometry_grids.clear()
    world_lighting.forget_reads()
    enabled_objects.forget()
    scene = getattr(bpy.context, "scene", None)
    if scene is not None and scene.penumbra.visibility.gpu_preview:
        update(scene)


def register():
    global _draw_handle
    for handlers, fn in ((bpy.app.handlers.frame_change_post, on_frame_change),
                         (bpy.app.handlers.depsgraph_update_post, on_depsgraph_update),
                         (bpy.app.handlers.load_post, on_load),
                         (bpy.app.handlers.undo_post, on_undo), (bpy.app.handlers.redo_post, on_undo)):
        if fn not in handlers:
            handlers.append(fn)
    if _draw_handle is None:
        _draw_handle = bpy.types.SpaceView3D.draw_handler_add(_draw, (), "WINDOW", "POST_VIEW")


def unregister():
    global _draw_handle
    if _draw_handle is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_draw_handle, "WINDOW")
        _draw_handle = None
    for handlers, fn in ((bpy.app.handlers.frame_change_post, on_frame_change),
                         (bpy.app.handlers.depsgraph_update_post, on_depsgraph_update),
                         (bpy.app.handlers.load_post, on_load),
                         (bpy.app.handlers.undo_post, on_undo), (bpy.app.handlers.redo_post, on_undo)):
        while fn in handlers:
            handlers.remove(fn)
    _previews.clear()
    _mesh_buffers.clear()
    _uniform_cache.clear()
    _geometry_grids.clear()
    enabled_objects.forget()
    _shaders.clear()
    gpu_model._shaders.clear()

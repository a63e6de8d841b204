"""The pose model on the GPU (issue 27): uploaded once per model as textures
(model_shader.py says what each holds), evaluated per vertex in the preview's
vertex shader with the §4.3 steps of preview_shader.py. Per frame only the
pose's features, the world matrix and the lighting (uniform blocks) and the
evaluated mesh's positions (one texture) go to the GPU; the shader takes the
vertex normals from them by Blender's rule, as the CPU shading does.

Why the evaluated mesh and not skinning in the shader: Blender evaluates the
armature (and any other deform, shape keys included) on the CPU for its own
drawing anyway, and reading its positions costs 0.4 ms at 100k vertices;
uploading them keeps the GPU exactly on the CPU's geometry for every
modifier stack, where skinning in the shader would need the armature
modifier's exact rule (weights normalization, preserve volume, multi
modifiers) and a fallback for every other deform, to save that read.
docs/visibility-gpu-preview-benchmark.md has what each step costs.

Needs a GPU context (a viewport draw, xvfb-run, or gpu.init() in bpy 5.x).
"""

import weakref

import numpy as np

from . import model_shader, preview_shader

_live = weakref.WeakSet()  # every ModelOnGpu not yet freed (live_texture_count)
_shaders = {}  # (order, lobes, brdf, readback, width, feature vec4s) -> GPUShader


def shader_info(order):
    """A shader's description with the SH order's defines."""
    import gpu
    info = gpu.types.GPUShaderCreateInfo()
    info.define("ORDER", str(order))
    info.define("NC", str(order * order))
    return info


def finish_shader(info, readback, vertex_source, name):
    """The stage interface, push constants and fragment stage both preview
    paths share (readback: one vertex a pixel of an RGBA32F buffer; else the
    viewport's triangles), then the compiled shader."""
    import gpu
    interface = gpu.types.GPUStageInterfaceInfo(f"{name}_{'readback' if readback else 'view'}")
    if readback:
        interface.flat("VEC4", "result")
        info.push_constant("VEC2", "readback_size")
        fragment = preview_shader.FRAGMENT_READBACK
    else:
        interface.smooth("VEC3", "shade")
        info.push_constant("MAT4", "ViewProjectionMatrix")
        info.push_constant("FLOAT", "depth_bias")
        fragment = preview_shader.FRAGMENT_VIEWPORT
    info.vertex_out(interface)
    info.fragment_out(0, "VEC4", "fragColor")
    info.vertex_source(vertex_source)
    info.fragment_source(fragment)
    return gpu.shader.create_from_info(info)


def read_back(shader, vertices, vertex_count, bind, readback_width=1024):
    """Draws `vertices` (a GPUVertBuf) as points with `shader`, one vertex a
    pixel of an RGBA32F offscreen buffer, after bind(shader) set its inputs,
    and reads it back: (rgb (V, 3), visibility (V,)) float32, unclamped."""
    import gpu
    n = vertex_count
    width = min(readback_width, max(n, 1))
    height = max(1, -(-n // width))
    batch = gpu.types.GPUBatch(type="POINTS", buf=vertices)
    offscreen = gpu.types.GPUOffScreen(width, height, format="RGBA32F")
    pixels = gpu.types.Buffer("FLOAT", width * height * 4)  # flat: 3.4's 3D Buffer gives numpy wrong strides
    try:
        with offscreen.bind():
            framebuffer = gpu.state.active_framebuffer_get()
            framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0))
            gpu.state.blend_set("NONE")
            gpu.state.depth_test_set("NONE")
            if hasattr(gpu.state, "program_point_size_set"):
                gpu.state.program_point_size_set(True)
            shader.bind()
            bind(shader)
            shader.uniform_float("readback_size", (float(width), float(height)))
            batch.draw(shader)
            framebuffer.read_color(0, 0, width, height, 4, 0, "FLOAT", data=pixels)
            if hasattr(gpu.state, "program_point_size_set"):
                gpu.state.program_point_size_set(False)
    finally:
        offscreen.free()
    flat = np.asarray(pixels, dtype=np.float32).reshape(-1, 4)[:n]
    return np.ascontiguousarray(flat[:, :3]), np.ascontiguousarray(flat[:, 3])


def shader_for(order, lobes, brdf, readback, width, feature_vec4s):
    key = (order, lobes, brdf, readback, width, feature_vec4s)
    shader = _shaders.get(key)
    if shader is not None:
        return shader
    info = shader_info(order)
    info.vertex_in(0, "INT", "p_vertex")
    for slot, name in enumerate(("model_weights", "model_bias", "model_blocks", "model_layout", "model_corners",
                                 "model_loops", "frame_geometry")):
        info.sampler(slot, "FLOAT_2D", name)
    info.typedef_source(preview_shader.uniform_block_source(order) + model_shader.pose_block_source(feature_vec4s))
    info.uniform_buf(0, "PenumbraShading", "shading")
    info.uniform_buf(1, "PenumbraPose", "pose")
    shader = finish_shader(info, readback, preview_shader.vertex_source(
        order, lobes, brdf, readback, model_texture_width=width), "penumbra_model")
    _shaders[key] = shader
    return shader


def _texture(size, flat, texture_format):
    import gpu
    return gpu.types.GPUTexture(size, format=texture_format, data=gpu.types.Buffer("FLOAT", flat.size, flat))


class ModelOnGpu:
    """One model's textures, its vertex-index buffer and triangles: made once,
    kept while the model and mesh stay the same. polygons: (sizes, vertex
    loops) as mesh_data.polygon_topology gives them. `layout` names each
    texture's (width, height), `bytes` what they and the buffers take."""

    def __init__(self, model, neighbours, polygons, triangles=None):
        import gpu
        self.order, self.lobes, self.vertex_count = model.order, model.lobes, model.vertex_count
        self.max_texture_size = gpu.capabilities.max_texture_size_get()
        self.width = model_shader.texture_width(self.max_texture_size)
        blocks = model.stored_blocks()
        self.feature_count = int(blocks["feature_offsets"][-1])
        self.feature_vec4s = model_shader.feature_vec4_count(self.feature_count)
        self.textures, self.layout, self.bytes = {}, {}, 0
        formats = {"model_weights": ("RGBA16F", 8), "model_loops": ("R32F", 4)}
        for name, texels in model_shader.pack_model(blocks, model.order, model.lobes, neighbours, *polygons).items():
            texture_format, texel_bytes = formats.get(name, ("RGBA32F", 16))
            size, flat = model_shader.grid_array(texels.reshape(-1, 4 if texel_bytes != 4 else 1), self.width,
                                                 self.max_texture_size)
            self.textures[name] = _texture(size, flat, texture_format)
            self.layout[name] = size
            self.bytes += size[0] * size[1] * texel_bytes
        vertex_format = gpu.types.GPUVertFormat()
        vertex_format.attr_add(id="p_vertex", comp_type="I32", len=1, fetch_mode="INT")
        self.vertices = gpu.types.GPUVertBuf(vertex_format, self.vertex_count)
        self.vertices.attr_fill("p_vertex", np.arange(self.vertex_count, dtype=np.int32))
        self.bytes += 4 * self.vertex_count
        self.triangles = None
        if triangles is not None:
            tri = np.ascontiguousarray(triangles, dtype=np.int32)
            self.triangles = gpu.types.GPUBatch(type="TRIS", buf=self.vertices,
                                                elem=gpu.types.GPUIndexBuf(type="TRIS", seq=tri))
            self.bytes += tri.nbytes
        self.pose_bytes = None  # the last uploaded PenumbraPose (what the viewport shows)
        self.shading_bytes = None  # and the last uploaded shading block
        _live.add(self)
        self.pose = None      # GPUUniformBuf, per frame
        self.shading = None   # GPUUniformBuf, per frame
        self.geometry = None  # GPUTexture, per frame

    def set_frame(self, frame):
        """Uploads one frame (FrameInputs): the geometry texture and both uniform blocks."""
        import gpu
        if isinstance(frame.geometry, tuple):
            size, flat = frame.geometry
        else:
            grid = model_shader.GeometryGrid(self.vertex_count, self.width, self.max_texture_size)
            size, flat = grid.fill(frame.geometry)
        self.geometry = _texture(size, flat, "R32F")
        self.pose_bytes, self.shading_bytes = frame.pose, frame.shading
        if self.pose is None:
            self.pose = gpu.types.GPUUniformBuf(frame.pose)
        else:
            self.pose.update(frame.pose)
        if self.shading is None or self.shading_size != len(frame.shading):
            self.shading = gpu.types.GPUUniformBuf(frame.shading)
            self.shading_size = len(frame.shading)
        else:
            self.shading.update(frame.shading)
        self.brdf = frame.brdf

    def bind(self, shader):
        for name, texture in self.textures.items():
            shader.uniform_sampler(name, texture)
        shader.uniform_sampler("frame_geometry", self.geometry)
        shader.uniform_block("shading", self.shading)
        shader.uniform_block("pose", self.pose)

    def draw(self, view_projection, depth_bias):
        shader = shader_for(self.order, self.lobes, self.brdf, False, self.width, self.feature_vec4s)
        shader.bind()
        self.bind(shader)
        shader.uniform_float("ViewProjectionMatrix", view_projection)
        shader.uniform_float("depth_bias", depth_bias)
        self.triangles.draw(shader)

    def shade_offscreen(self):
        """Every vertex shaded into an RGBA32F offscreen buffer, one a pixel,
        read back: (rgb (V, 3), visibility (V,)) float32, unclamped."""
        shader = shader_for(self.order, self.lobes, self.brdf, True, self.width, self.feature_vec4s)
        return read_back(shader, self.vertices, self.vertex_count, self.bind)


def live_texture_count():
    """GPU textures the preview's models hold now (the model's and the frame's):
    what an object's cleanup must bring back to its count before."""
    return sum(len(m.textures) + (m.geometry is not None) for m in list(_live))


class FrameInputs:
    """What one frame uploads, computed on the CPU: the positions (3V floats,
    model_shader.geometry_floats, or already a grid: ((W, H), flat)), the
    pose and shading uniform blocks' bytes, the BRDF."""

    def __init__(self, geometry, pose, shading, brdf):
        preview_shader.check_configuration(1, 1, brdf)
        self.geometry, self.pose, self.shading, self.brdf = geometry, pose, shading, brdf
        self.seconds = {}


def frame_inputs(model, features, positions, world, lighting, brdf="diffuse", phong_exponent=16.0,
                 camera=(0.0, 0.0, 0.0), transmission=(0.5, 0.5, 0.5)):
    """FrameInputs from object-space positions (V, 3), the world matrix (4, 4)
    and the lighting (order², 3): what PoseModel.shade takes after its world
    transform (the normals come from the positions, on the GPU)."""
    vec4s = model_shader.feature_vec4_count(len(features))
    return FrameInputs(model_shader.geometry_floats(positions),
                       model_shader.pose_data(features, vec4s, world),
                       preview_shader.uniform_data(model.order, lighting, brdf, phong_exponent, camera, transmission),
                       brdf)

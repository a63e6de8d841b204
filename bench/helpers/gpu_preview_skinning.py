"""Run by bench/visibility_gpu_preview_benchmark.py inside a Blender with a
GPU (3.4 in a window under Xvfb, or the bpy 5.x module with --gpu-init):

    .venv313/bin/python bench/helpers/gpu_preview_skinning.py --gpu-init --vertices 100000

Issue 27 item 1's choice, measured: skin in the vertex shader, or upload
Blender's evaluated mesh (what gpu_model.py does). A prototype, here only:
the preview's model shader with its one position fetch (geometry_at)
replaced by linear-blend skinning of the rest position (4 bones a vertex,
the object's normalized vertex-group weights, bone matrices in a uniform
block). Every position the shader reads is skinned: the vertex's own, its
reference neighbour's and every corner of its faces (the normals). Per frame
on the CPU: packing the bone matrices against reading the evaluated positions
(and each upload); on the GPU: the draw at 1280×720 and the per-vertex
readback of both shaders, and their largest difference (the prototype skins
as Blender's Armature modifier does, so both shade the same pose). Prints one
line `RESULT {json}`.
"""

import os
import statistics
import sys
import tempfile
import time

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path[:0] = [os.path.join(ROOT, "build", "addon"), os.path.join(ROOT, "examples", "scenes")]
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
VERTICES = int(ARGS[ARGS.index("--vertices") + 1]) if "--vertices" in ARGS else 100000
REPEATS = 20
MAX_BONES = 64

if "--gpu-init" in ARGS:
    import gpu
    gpu.init()

sys.path.append(ROOT)
import penumbra  # noqa: E402
from bench.helpers.blender_result import report  # noqa: E402
from bench.helpers.gpu_preview_scene import character, gpu_draw_seconds  # noqa: E402
from penumbra.visibility import frame_shading, gpu_model, gpu_preview, mesh_data, model_shader, preview_shader  # noqa

SKINNED_GEOMETRY = (
    "vec3 geometry_at(int i)\n{\n"
    "  vec3 rest = vec3(texelFetch(frame_geometry, texel_at(i), 0).r, texelFetch(frame_geometry, texel_at(i + 1), 0).r,\n"
    "                   texelFetch(frame_geometry, texel_at(i + 2), 0).r);\n"
    "  int v = i / 3;\n"
    "  vec4 bone = texelFetch(skin_weights, texel_at(2 * v), 0);\n"
    "  vec4 weight = texelFetch(skin_weights, texel_at(2 * v + 1), 0);\n"
    "  mat4 m = weight.x * bones.matrices[int(bone.x)] + weight.y * bones.matrices[int(bone.y)]\n"
    "         + weight.z * bones.matrices[int(bone.z)] + weight.w * bones.matrices[int(bone.w)];\n"
    "  return (m * vec4(rest, 1.0)).xyz;\n}\n")


def skinned_source(order, lobes, brdf, readback, width):
    """The preview's vertex source with geometry_at skinning the rest position."""
    source = preview_shader.vertex_source(order, lobes, brdf, readback, model_texture_width=width)
    helpers = model_shader.helper_source(width)
    start = helpers.index("vec3 geometry_at(int i)")
    end = helpers.index("int loop_vertex")
    assert helpers[start:end] in source
    return source.replace(helpers[start:end], SKINNED_GEOMETRY)


def skinned_shader(on_gpu, readback):
    import gpu
    info = gpu_model.shader_info(on_gpu.order)
    info.vertex_in(0, "INT", "p_vertex")
    for slot, name in enumerate(("model_weights", "model_bias", "model_blocks", "model_layout", "model_corners",
                                 "model_loops", "frame_geometry", "skin_weights")):
        info.sampler(slot, "FLOAT_2D", name)
    info.typedef_source(preview_shader.uniform_block_source(on_gpu.order)
                        + model_shader.pose_block_source(on_gpu.feature_vec4s)
                        + f"struct PenumbraBones {{\n  mat4 matrices[{MAX_BONES}];\n}};\n")
    info.uniform_buf(0, "PenumbraShading", "shading")
    info.uniform_buf(1, "PenumbraPose", "pose")
    info.uniform_buf(2, "PenumbraBones", "bones")
    source = skinned_source(on_gpu.order, on_gpu.lobes, on_gpu.brdf, readback, on_gpu.width)
    return gpu_model.finish_shader(info, readback, source, "penumbra_skinned")


def skin_weights(obj, groups):
    """(V, 2, 4) float32: each vertex's 4 largest weights' bone slots, then the weights normalized."""
    slot_of = {g.index: groups.index(g.name) for g in obj.vertex_groups if g.name in groups}
    out = np.zeros((len(obj.data.vertices), 2, 4), dtype=np.float32)
    for vertex in obj.data.vertices:
        pairs = sorted(((e.weight, slot_of[e.group]) for e in vertex.groups if e.group in slot_of), reverse=True)[:4]
        total = sum(w for w, _ in pairs) or 1.0
        for k, (w, slot) in enumerate(pairs):
            out[vertex.index, 0, k], out[vertex.index, 1, k] = slot, w / total
    return out


def bone_matrices(obj, armature, groups):
    """The bone matrices as the Armature modifier applies them, in the mesh's object space: (MAX_BONES, 4, 4)
    float32 bytes, column-major as GLSL reads a mat4."""
    to_armature = armature.matrix_world.inverted() @ obj.matrix_world
    from_armature = to_armature.inverted()
    out = np.zeros((MAX_BONES, 4, 4), dtype=np.float32)
    for slot, name in enumerate(groups):
        pose_bone = armature.pose.bones[name]
        out[slot] = from_armature @ pose_bone.matrix @ pose_bone.bone.matrix_local.inverted() @ to_armature
    return np.ascontiguousarray(out.transpose(0, 2, 1)).tobytes()


def ms(samples):
    return round(1000.0 * statistics.median(samples), 3)


def cpu_per_frame(scene, obj, armature, groups):
    """Per-frame CPU, ms (medians over REPEATS frames): the evaluated positions read and uploaded
    (the preview's route) against the bone matrices packed and uploaded (skinning)."""
    import gpu
    entry = frame_shading.loaded_model(obj)
    read, pack, upload_positions, upload_bones = [], [], [], []
    buffer = None
    for k in range(REPEATS):
        scene.frame_set(2 + k % 20)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        t = time.perf_counter()
        frame_shading._read_positions(obj, depsgraph, entry)
        read.append(time.perf_counter() - t)
        grid = model_shader.GeometryGrid(entry.model.vertex_count, model_shader.texture_width(16384), 16384)
        size, flat = grid.fill(entry.positions)
        t = time.perf_counter()
        gpu_model._texture(size, flat, "R32F")
        upload_positions.append(time.perf_counter() - t)
        t = time.perf_counter()
        matrices = bone_matrices(obj, armature, groups)
        pack.append(time.perf_counter() - t)
        t = time.perf_counter()
        if buffer is None:
            buffer = gpu.types.GPUUniformBuf(matrices)
        else:
            buffer.update(matrices)
        upload_bones.append(time.perf_counter() - t)
    return {"read_positions_ms": ms(read), "upload_positions_ms": ms(upload_positions),
            "pack_bones_ms": ms(pack), "upload_bones_ms": ms(upload_bones), "bones": len(groups)}


def gpu_costs(scene, obj, armature, groups):
    """Draw (1280×720) and readback of the preview's shader and the skinning prototype at one pose."""
    import gpu
    entry, frame = gpu_preview.frame_of(obj, scene)
    on_gpu = gpu_model.ModelOnGpu(entry.model, entry.neighbours, mesh_data.polygon_topology(obj.data),
                                  entry.buffers.triangles)
    on_gpu.set_frame(frame)
    rest = np.empty(3 * len(obj.data.vertices), dtype=np.float32)
    obj.data.vertices.foreach_get("co", rest)
    grid = model_shader.GeometryGrid(on_gpu.vertex_count, on_gpu.width, on_gpu.max_texture_size)
    rest_texture = gpu_model._texture(*grid.fill(rest), "R32F")
    size, flat = model_shader.grid_array(skin_weights(obj, groups).reshape(-1, 4), on_gpu.width,
                                         on_gpu.max_texture_size)
    weights_texture = gpu_model._texture(size, flat, "RGBA32F")
    bones = gpu.types.GPUUniformBuf(bone_matrices(obj, armature, groups))

    def bind_skinned(shader):
        on_gpu.bind(shader)
        shader.uniform_sampler("frame_geometry", rest_texture)
        shader.uniform_sampler("skin_weights", weights_texture)
        shader.uniform_block("bones", bones)

    view = skinned_shader(on_gpu, False)

    def draw_skinned(view_projection):
        shader = view
        shader.bind()
        bind_skinned(shader)
        shader.uniform_float("ViewProjectionMatrix", view_projection)
        shader.uniform_float("depth_bias", gpu_preview.DEPTH_BIAS)
        on_gpu.triangles.draw(shader)

    readback = skinned_shader(on_gpu, True)
    timed = {}
    for name, shade in (("evaluated", on_gpu.shade_offscreen),
                        ("skinned", lambda: gpu_model.read_back(readback, on_gpu.vertices, on_gpu.vertex_count,
                                                                bind_skinned))):
        samples = []
        for _ in range(4):
            t = time.perf_counter()
            timed[name] = shade()
            samples.append(time.perf_counter() - t)
        timed[name + "_readback_ms"] = ms(samples[1:])
    draw_evaluated = gpu_draw_seconds(lambda vp: on_gpu.draw(vp, gpu_preview.DEPTH_BIAS), repeats=3)
    draw_skinned = gpu_draw_seconds(draw_skinned, repeats=3)
    return {"draw_evaluated_ms": round(1000.0 * draw_evaluated[0], 1),
            "draw_skinned_ms": round(1000.0 * draw_skinned[0], 1),
            "readback_evaluated_ms": timed["evaluated_readback_ms"], "readback_skinned_ms": timed["skinned_readback_ms"],
            "max_abs_skinned_vs_evaluated": float(np.abs(timed["skinned"][0] - timed["evaluated"][0]).max()),
            "skin_bytes_per_vertex": 32 + 12}  # 2 RGBA32F texels + the rest positions (R32F)


def measure(result):
    import gpu
    penumbra.register()
    result["renderer"] = f"{gpu.platform.renderer_get()} / {gpu.platform.version_get()}"
    with tempfile.TemporaryDirectory() as tmp:
        scene, obj = character(VERTICES, tmp)
        armature = obj.parent
        groups = [g.name for g in obj.vertex_groups if g.name in armature.pose.bones]
        result.update(vertices=len(obj.data.vertices), load_average=round(os.getloadavg()[0], 2))
        result.update(cpu_per_frame(scene, obj, armature, groups))
        scene.frame_set(9)
        result.update(gpu_costs(scene, obj, armature, groups))


report(measure)

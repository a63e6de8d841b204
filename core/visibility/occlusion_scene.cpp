#include "visibility/occlusion_scene.hpp"

#include <cmath>
#include <limits>
#include <string>

#include <embree3/rtcore.h>

#include "common/error.hpp"

namespace penumbra::visibility {

struct OcclusionScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    int width = 1;
    SceneBuild build = SceneBuild::Medium;
    struct Part {
        RTCGeometry geometry = nullptr;
        float* vertices = nullptr;
        std::size_t vertex_count = 0;
        std::vector<std::uint32_t> triangles;
    };
    std::vector<Part> parts;       // one per mesh given, empty ones included (geometry null)

    ~Impl() {
        for (auto& p : parts)
            if (p.geometry) rtcReleaseGeometry(p.geometry);
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

namespace {

// The process-wide device, created once (thread-safe static initialization)
// and never released: releasing it at exit could race Embree's own teardown.
// Each scene holds a reference of its own.
RTCDevice shared_device() {
    static RTCDevice device = rtcNewDevice(nullptr);
    return device;
}

void check_device(RTCDevice device, const char* what) {
    const RTCError code = rtcGetDeviceError(device);
    if (code != RTC_ERROR_NONE)
        throw Error(std::string("Embree failed while ") + what + " (error " + std::to_string(int(code)) + ")");
}

void validate(const TriangleMesh& mesh, std::size_t index) {
    const std::string name = "mesh " + std::to_string(index);
    if (mesh.positions.size() % 3 != 0 || mesh.triangles.size() % 3 != 0)
        throw ArgumentError(name + ": positions and triangles must hold whole triples");
    for (float x : mesh.positions)
        if (!std::isfinite(x)) throw ArgumentError(name + " has a non-finite vertex position");
    const std::size_t n = mesh.vertex_count();
    for (std::uint32_t i : mesh.triangles)
        if (i >= n)
            throw ArgumentError(name + ": triangle index " + std::to_string(i) + " is out of range (" +
                                std::to_string(n) + " vertices)");
}

}  // namespace

OcclusionScene::OcclusionScene(const std::vector<const TriangleMesh*>& meshes, SceneBuild build, Traversal traversal)
    : impl_(std::make_unique<Impl>()) {
    if (traversal != Traversal::Fast && traversal != Traversal::Robust) throw ArgumentError("unknown traversal");
    for (std::size_t k = 0; k < meshes.size(); ++k) validate(*meshes[k], k);
    impl_->device = shared_device();
    if (!impl_->device) throw Error("Embree could not create a device (rtcNewDevice failed)");
    rtcRetainDevice(impl_->device);
    impl_->build = build;
    if (rtcGetDeviceProperty(impl_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED))
        impl_->width = 16;
    else if (rtcGetDeviceProperty(impl_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED))
        impl_->width = 8;
    else if (rtcGetDeviceProperty(impl_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED))
        impl_->width = 4;
    impl_->scene = rtcNewScene(impl_->device);
    if (!impl_->scene) {
        check_device(impl_->device, "creating a scene");
        throw Error("Embree could not create a scene");
    }
    const int flags = (traversal == Traversal::Robust ? RTC_SCENE_FLAG_ROBUST : 0) |
                      (build == SceneBuild::Low ? RTC_SCENE_FLAG_DYNAMIC : 0);
    rtcSetSceneFlags(impl_->scene, RTCSceneFlags(flags));
    rtcSetSceneBuildQuality(impl_->scene, build == SceneBuild::High  ? RTC_BUILD_QUALITY_HIGH
                                          : build == SceneBuild::Low ? RTC_BUILD_QUALITY_LOW
                                                                     : RTC_BUILD_QUALITY_MEDIUM);
    for (const TriangleMesh* mesh : meshes) {
        Impl::Part part;
        part.vertex_count = mesh->vertex_count();
        part.triangles = mesh->triangles;
        if (mesh->triangle_count() == 0) {
            impl_->parts.push_back(std::move(part));
            continue;
        }
        RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (build == SceneBuild::Refit) rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_REFIT);
        else if (build == SceneBuild::Low) rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_LOW);
        // Embree reads vertices with 16-byte loads: one float of padding at the end.
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh->vertex_count() + 1));
        auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), mesh->triangle_count()));
        if (!vertices || !indices) {
            rtcReleaseGeometry(geometry);
            check_device(impl_->device, "allocating geometry buffers");
            throw Error("Embree could not allocate geometry buffers");
        }
        std::copy(mesh->positions.begin(), mesh->positions.end(), vertices);
        vertices[mesh->positions.size()] = vertices[mesh->positions.size() + 1] = vertices[mesh->positions.size() + 2] = 0.0f;
        std::copy(mesh->triangles.begin(), mesh->triangles.end(), indices);
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(impl_->scene, geometry);
        part.geometry = geometry;  // the scene holds a reference too; ours is released in ~Impl
        part.vertices = vertices;
        impl_->parts.push_back(std::move(part));
    }
    rtcCommitScene(impl_->scene);
    check_device(impl_->device, "building the scene");
}

bool OcclusionScene::update_positions(const std::vector<const TriangleMesh*>& meshes) {
    if (meshes.size() != impl_->parts.size()) return false;
    for (std::size_t k = 0; k < meshes.size(); ++k)
        if (meshes[k]->vertex_count() != impl_->parts[k].vertex_count || meshes[k]->triangles != impl_->parts[k].triangles)
            return false;
    for (std::size_t k = 0; k < meshes.size(); ++k) validate(*meshes[k], k);
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        Impl::Part& part = impl_->parts[k];
        if (!part.geometry) continue;
        std::copy(meshes[k]->positions.begin(), meshes[k]->positions.end(), part.vertices);
        rtcUpdateGeometryBuffer(part.geometry, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(part.geometry);
    }
    rtcCommitScene(impl_->scene);
    check_device(impl_->device, "updating the scene");
    return true;
}

OcclusionScene::~OcclusionScene() = default;

int OcclusionScene::packet_width() const { return impl_->width; }

namespace {

// Casts rays [0, count) (count <= W) as one packet: lane i from origin(i)
// along direction(i); writes occluded[i].
template <int W, typename Packet, typename Origin, typename Direction>
void cast_lanes(RTCScene scene, RTCIntersectContext& context, const Origin& origin, const Direction& direction,
                int count, float t_near, float t_far, std::uint8_t* occluded,
                void (*occluded_fn)(const int*, RTCScene, RTCIntersectContext*, Packet*)) {
    alignas(64) Packet packet;
    alignas(64) int valid[W];
    for (int i = 0; i < W; ++i) {
        const bool live = i < count;
        valid[i] = live ? -1 : 0;
        const Eigen::Vector3f& o = origin(live ? i : 0);
        const Eigen::Vector3f& d = direction(live ? i : 0);
        packet.org_x[i] = o.x();
        packet.org_y[i] = o.y();
        packet.org_z[i] = o.z();
        packet.dir_x[i] = d.x();
        packet.dir_y[i] = d.y();
        packet.dir_z[i] = d.z();
        packet.tnear[i] = t_near;
        packet.tfar[i] = t_far;
        packet.time[i] = 0.0f;
        packet.mask[i] = 0xFFFFFFFFu;
        packet.id[i] = 0;
        packet.flags[i] = 0;
    }
    occluded_fn(valid, scene, &context, &packet);
    // Embree sets tfar to −inf for an occluded ray.
    for (int i = 0; i < count; ++i) occluded[i] = packet.tfar[i] < 0.0f ? 1 : 0;
}

template <int W, typename Packet>
void cast_packet(RTCScene scene, const Eigen::Vector3f& origin, const Eigen::Vector3f* directions, int count,
                 float t_near, float t_far, std::uint8_t* occluded,
                 void (*occluded_fn)(const int*, RTCScene, RTCIntersectContext*, Packet*)) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (int start = 0; start < count; start += W)
        cast_lanes<W>(scene, context, [&](int) -> const Eigen::Vector3f& { return origin; },
                      [&](int i) -> const Eigen::Vector3f& { return directions[start + i]; },
                      std::min(W, count - start), t_near, t_far, occluded + start, occluded_fn);
}

template <int W, typename Packet>
void cast_rays(RTCScene scene, const Eigen::Vector3f* origins, const Eigen::Vector3f* directions, int count,
               float t_near, float t_far, std::uint8_t* occluded,
               void (*occluded_fn)(const int*, RTCScene, RTCIntersectContext*, Packet*)) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    cast_lanes<W>(scene, context, [&](int i) -> const Eigen::Vector3f& { return origins[i]; },
                  [&](int i) -> const Eigen::Vector3f& { return directions[i]; }, count, t_near, t_far, occluded,
                  occluded_fn);
}

}  // namespace

void OcclusionScene::occluded_bundle(const Eigen::Vector3f& origin, const Eigen::Vector3f* directions, int count,
                                     float t_near, float t_far, std::uint8_t* occluded, bool use_packets) const {
    switch (use_packets ? impl_->width : 1) {
        case 16: cast_packet<16, RTCRay16>(impl_->scene, origin, directions, count, t_near, t_far, occluded, rtcOccluded16); return;
        case 8: cast_packet<8, RTCRay8>(impl_->scene, origin, directions, count, t_near, t_far, occluded, rtcOccluded8); return;
        case 4: cast_packet<4, RTCRay4>(impl_->scene, origin, directions, count, t_near, t_far, occluded, rtcOccluded4); return;
        default:
            for (int i = 0; i < count; ++i) occluded[i] = occluded1(origin, directions[i], t_near, t_far) ? 1 : 0;
    }
}

void OcclusionScene::occluded_packet(const Eigen::Vector3f* origins, const Eigen::Vector3f* directions, int count,
                                     float t_near, float t_far, std::uint8_t* occluded, int width) const {
    if (width == 0) width = impl_->width;
    if (count < 0 || count > width) throw ArgumentError("a packet holds 0.." + std::to_string(width) + " rays");
    switch (width) {
        case 16: cast_rays<16, RTCRay16>(impl_->scene, origins, directions, count, t_near, t_far, occluded, rtcOccluded16); return;
        case 8: cast_rays<8, RTCRay8>(impl_->scene, origins, directions, count, t_near, t_far, occluded, rtcOccluded8); return;
        case 4: cast_rays<4, RTCRay4>(impl_->scene, origins, directions, count, t_near, t_far, occluded, rtcOccluded4); return;
        case 1:
            for (int i = 0; i < count; ++i) occluded[i] = occluded1(origins[i], directions[i], t_near, t_far) ? 1 : 0;
            return;
        default: throw ArgumentError("packet width must be 0 (native), 1, 4, 8 or 16");
    }
}

bool OcclusionScene::occluded1(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near,
                               float t_far) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray;
    ray.org_x = origin.x();
    ray.org_y = origin.y();
    ray.org_z = origin.z();
    ray.dir_x = direction.x();
    ray.dir_y = direction.y();
    ray.dir_z = direction.z();
    ray.tnear = t_near;
    ray.tfar = t_far;
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(impl_->scene, &context, &ray);
    return ray.tfar < 0.0f;
}

}  // namespace penumbra::visibility

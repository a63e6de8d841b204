// Angular-region tables (paper §4.1): for a surface normal (or a reflection
// direction), the subset of lights that can contribute, found in constant
// time through a cube map.
//
// Regions are the cells of a cube map with `cells_per_face`² cells per face
// (6·g² regions; g = 6 gives 216, the paper used about 200). A direction's
// region is the cell its cube-map projection falls in (largest-magnitude
// axis picks the face, the other two coordinates the cell). Each region has a
// centre P (the cell centre pushed onto the sphere) and radius α/2 (the
// largest angle between P and any direction in the cell, at a corner). A
// light belongs to the region when its angle from P is at most
// β = α/2 + lobe, lobe = π/2 for diffuse shading (every light above the
// horizon of some normal in the cell), narrower for a glossy lobe around a
// reflection direction. So shading a normal n with only its region's lights
// misses no light with n·d > 0: irradiance_culled equals irradiance exactly,
// while visiting on average about (1 + sin(α/2))/2 of the lights for the
// diffuse lobe (the paper's "theoretical speedup of 2").
#pragma once

#include <vector>

#include <Eigen/Core>

#include "lights/frame_lights.hpp"

namespace penumbra::lights {

class AngularRegionTable {
public:
    AngularRegionTable(const std::vector<Eigen::Vector3d>& light_directions, int cells_per_face = 6,
                       double lobe_half_angle = 1.5707963267948966);

    int cells_per_face() const { return g_; }
    int region_count() const { return 6 * g_ * g_; }
    // Region index = (face · g + row) · g + column; faces +x, −x, +y, −y, +z, −z.
    int region_of(const Eigen::Vector3d& direction) const;
    Eigen::Vector3d centre(int region) const;
    double radius(int region) const { return radius_[region]; }  // α/2
    // Lights of a region: indices into the direction list, ascending.
    const int* begin(int region) const { return items_.data() + offsets_[region]; }
    const int* end(int region) const { return items_.data() + offsets_[region + 1]; }
    const std::vector<int>& offsets() const { return offsets_; }  // region_count + 1 (CSR)
    const std::vector<int>& items() const { return items_; }

private:
    Eigen::Vector3d cube_point(int face, double s, double t) const;
    int g_;
    std::vector<double> radius_;
    std::vector<int> offsets_, items_;
};

// Irradiance through the table: only the normal's region's lights are visited.
// `visited` (optional) receives the total number of light visits.
Eigen::MatrixXd irradiance_culled(const AngularRegionTable& table, const std::vector<Light>& lights,
                                  const std::vector<Eigen::Vector3d>& normals, std::size_t* visited = nullptr);

}  // namespace penumbra::lights

// A uniform grid over [−1, 1]³ holding unit vectors: nearest-direction and
// within-angle queries for the region assignment and the clustering (the
// paper uses Arya et al.'s BBD tree; a grid does the same job for points on
// a sphere at these counts).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace penumbra::lights {

class DirectionIndex {
public:
    // `cells` per axis; 0 picks about one direction per cell on the sphere.
    explicit DirectionIndex(const std::vector<Eigen::Vector3d>& directions, int cells = 0);

    // Index of the direction with the largest dot product with `d` (ties: the
    // lowest index); −1 when empty.
    int nearest(const Eigen::Vector3d& d) const;

    // Indices i (ascending) with angle(d, directions[i]) <= angle.
    void within(const Eigen::Vector3d& d, double angle, std::vector<int>& out) const;

private:
    int cell_of(double coordinate) const;
    const std::vector<Eigen::Vector3d>* directions_;
    int n_;
    double size_;
    std::vector<int> start_, items_;
};

}  // namespace penumbra::lights

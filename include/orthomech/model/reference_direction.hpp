#pragma once
// The default reference direction of an axis (docs/file-format.md, spatial joints' `ref`): the
// frame axis least aligned with the axis direction h (x before y before z on a tie), projected
// perpendicular to h and normalised. The one rule of the spatial reader (io/spatial_file.cpp)
// and of the RSSR synthesis' axis frames (synthesis/rssr.hpp).
#include <Eigen/Core>
#include <cmath>

namespace orthomech {

// h: a unit vector (its components in the frame whose axes are chosen from). Components equal
// to within 1e-9 are a tie, so that the round-off of a rotation (h = (1e-17, 0, 1)) does not
// decide it.
[[nodiscard]] inline Eigen::Vector3d least_aligned(const Eigen::Vector3d& h) {
  constexpr double kTie = 1e-9;
  const double smallest = h.cwiseAbs().minCoeff();
  int k = 0;
  while (std::abs(h(k)) > smallest + kTie) ++k;
  const Eigen::Vector3d e = Eigen::Vector3d::Unit(k);
  return (e - e.dot(h) * h).normalized();
}

}  // namespace orthomech

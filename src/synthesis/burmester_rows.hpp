#pragma once
// Internal to src/synthesis (motion_generation.cpp, motion_few_poses.cpp): the normalised poses
// and the compatibility rows (L15) of Burmester theory shared by the 2–4 pose functions and the
// 5-and-more pose generator (docs/synthesis.md, "Motion generation").
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "orthomech/synthesis/motion_generation.hpp"

namespace orthomech::synthesis::detail {

using Mat2 = Eigen::Matrix2d;

inline Mat2 rotation(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Mat2 R;
  R << c, -s, s, c;
  return R;
}

inline Vec2 perp(const Vec2& v) { return {-v.y(), v.x()}; }
inline double cross(const Vec2& u, const Vec2& v) { return u.x() * v.y() - u.y() * v.x(); }

// The poses translated to their centroid and scaled by their RMS spread (conditioning).
struct Normalised {
  std::vector<Vec2> P;
  std::vector<Mat2> R;
  Vec2 centre = Vec2::Zero();
  double scale = 1.0;
};

inline Normalised normalise(const std::vector<Pose>& poses) {
  Normalised n;
  for (const Pose& p : poses) n.centre += p.position;
  n.centre /= static_cast<double>(poses.size());
  double spread = 0.0;
  for (const Pose& p : poses) spread += (p.position - n.centre).squaredNorm();
  spread = std::sqrt(spread / static_cast<double>(poses.size()));
  n.scale = spread > 0.0 ? spread : 1.0;
  for (const Pose& p : poses) {
    n.P.emplace_back((p.position - n.centre) / n.scale);
    n.R.push_back(rotation(p.angle));
  }
  return n;
}

// (L15): g_j = a_j(m)·z + c_j(m) with
//   a_j(m) = 2 (R_jᵀP_j − R_1ᵀP_1) − 2 (R_j − R_1)ᵀ m,  c_j(m) = |P_j|² − |P_1|² − 2 (P_j − P_1)·m.
inline Eigen::Vector3d compatibility_row(const Normalised& n, std::size_t j, const Vec2& m) {
  const Vec2 a = 2.0 * (n.R[j].transpose() * n.P[j] - n.R[0].transpose() * n.P[0]) -
                 2.0 * (n.R[j] - n.R[0]).transpose() * m;
  const double c = n.P[j].squaredNorm() - n.P[0].squaredNorm() - 2.0 * (n.P[j] - n.P[0]).dot(m);
  return {a.x(), a.y(), c};
}

// The circle point z of centre m from the rows `rows` (least squares, rows ≥ 2).
inline Vec2 circle_point_of(const Normalised& n, const std::vector<std::size_t>& rows,
                            const Vec2& m) {
  Eigen::MatrixXd A(static_cast<Eigen::Index>(rows.size()), 2);
  Eigen::VectorXd rhs(A.rows());
  for (Eigen::Index i = 0; i < A.rows(); ++i) {
    const Eigen::Vector3d row = compatibility_row(n, rows[static_cast<std::size_t>(i)], m);
    A.row(i) = row.head<2>().transpose();
    rhs(i) = -row(2);
  }
  return A.colPivHouseholderQr().solve(rhs);
}

// The dyad (m, z) in world units with its radius and residual over all poses.
inline Dyad make_dyad(const std::vector<Pose>& poses, const Vec2& m, const Vec2& z) {
  Dyad d;
  d.fixed_pivot = m;
  d.moving_pivot = z;
  std::vector<double> r;
  r.reserve(poses.size());
  for (const Pose& p : poses) r.push_back((p.position + rotation(p.angle) * z - m).norm());
  for (const double ri : r) d.radius += ri / static_cast<double>(r.size());
  for (const double ri : r) d.residual = std::max(d.residual, std::abs(ri - d.radius));
  return d;
}

inline Dyad to_world(const std::vector<Pose>& poses, const Normalised& n, const Vec2& m,
                     const Vec2& z) {
  return make_dyad(poses, n.centre + n.scale * m, n.scale * z);
}

}  // namespace orthomech::synthesis::detail

#pragma once
// Spatial joints (docs/spatial.md §2): every joint type is a list of rows, each one of five
// primitives, defined once in the table below (its rows, their names, and which coordinate the
// joint has). The primitives, for body i (first of `connects`) and j (second), P_i, P_j the joint
// points, a_i, a_j body-fixed unit vectors (columns of the joint frames), d = r_Pj − r_Pi:
//   point  (P1)  f = c·(r_Pi − r_Pj), c a world axis x, y or z
//   dot1   (P2)  f = a_i·a_j
//   dot2   (P3)  f = a_i·d
//   length (P4)  f = (d·d − L²)/(2L)
//   screw  (S6)  f = (p/2π)·wrap(2π z/p − θ), z = h_i·d, θ the (P5) twist angle of f_j about h_i
// Each gives its rate as Σ_b (g_b·v_b + h_b·w_b); Eᵀ, Dᵀ and Dᵀu follow by the generic rule
// (R1)–(R3) (model/spatial.hpp: add_spatial_row, add_spatial_row_rate).
#include <array>

#include "orthomech/model/model.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

enum class SpatialPrimitive { point, dot1, dot2, length, screw };
// Which coordinate a joint has (its `joint` measure, drivers, limits).
enum class SpatialCoordinate { none, angle, slide };

struct SpatialRowSpec {
  SpatialPrimitive primitive = SpatialPrimitive::point;
  int a = 0;  // point: world axis 0/1/2; dot1, dot2: column of frame_i (0 f, 1 g, 2 h)
  int b = 0;  // dot1: column of frame_j
  const char* name = "";
};

struct SpatialJointSpec {
  const char* type;  // as written in files
  int rows;
  std::array<SpatialRowSpec, 6> row;
  SpatialCoordinate coordinate;
};

// The one table of spatial joint types, indexed by SpatialJointType (docs/spatial.md §2.4).
[[nodiscard]] const SpatialJointSpec& spatial_joint_spec(SpatialJointType type);
// The type whose name is `name`; false if there is none.
[[nodiscard]] bool find_spatial_joint_type(const std::string& name, SpatialJointType& type);

// The (P5) twist angle θ of a direction f_j (fixed in j) about h_i, measured from f_i towards g_i
// (f_i, g_i, h_i fixed in i, world components): θ = atan2(g_i·f_j, f_i·f_j), with
// θ̇ = (w_i − w_j)·k and k̇ its rate along the motion.
struct TwistAngle {
  double theta = 0.0;
  Vec3 k = Vec3::Zero();
  Vec3 kdot = Vec3::Zero();
};
[[nodiscard]] TwistAngle twist_angle(const Vec3& fi, const Vec3& gi, const Vec3& fj, const Vec3& wi,
                                     const Vec3& wj);

// Rows of one spatial joint from row r on: f (if f), Eᵀ (if Et), Dᵀ (if Dt), Dᵀu (if Dtu, needs
// u). Its rows of Eᵀ and Dᵀ are added into: they must be zero on entry (compute_constraints
// zeroes the matrices once). Allocation-free.
// EtT: MatX, SparseEt or EtRecorder (constraints/sparse_et.hpp; instantiated for the three).
// rotations: R(e_b) of every body at q (BodyPoses::spatial_table), or null.
template <typename EtT>
void evaluate_spatial_joint(const Model& model, const SpatialJoint& joint, const VecX& q,
                            const VecX* u, int r, VecX* f, EtT* Et, MatX* Dt, VecX* Dtu,
                            const Mat3* rotations = nullptr);

// The joint's coordinate at (q, u) (u may be null): the angle (revolute, cylindrical, screw: the
// twist angle of ref_j about h_i from f_i, in (−π, π]) or the slide h_i·d (prismatic). Throws
// std::invalid_argument for a joint type without a coordinate.
[[nodiscard]] SpatialScalar spatial_joint_coordinate(const Model& model, const SpatialJoint& joint,
                                                     const VecX& q, const VecX* u);

// The reaction of a spatial joint (docs/spatial.md (S7)): the wrench that body j exerts on body i
// through the joint's rows with multipliers λ (its rows only), F = (Eλ)_{v_i} and the moment about
// the joint point, world components: about P_i, or about P_j for point-on-line, point-on-plane
// and distance (where the moment vanishes). When body i is the ground, minus body j's share. Also
// in the joint frame of body i at q (the fixed world frame when body i is the ground).
struct SpatialWrench {
  Vec3 force = Vec3::Zero(), moment = Vec3::Zero();              // world
  Vec3 force_local = Vec3::Zero(), moment_local = Vec3::Zero();  // joint frame (f, g, h)
};
[[nodiscard]] SpatialWrench spatial_joint_reaction(const Model& model, const SpatialJoint& joint,
                                                   const VecX& q,
                                                   const Eigen::Ref<const VecX>& lambda);

}  // namespace orthomech

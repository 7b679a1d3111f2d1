#include "orthomech/analysis/reactions.hpp"

#include <type_traits>

#include "orthomech/constraints/rolling_disc.hpp"
#include "orthomech/constraints/spatial_joints.hpp"

namespace orthomech {

std::vector<ReactionComponent> reaction_components(const Model& model) {
  std::vector<ReactionComponent> out;
  for (size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    const int ji = static_cast<int>(j);
    auto add = [&](const std::string& c, bool global, const char* unit) {
      out.push_back({joint.name + "." + c, ji, global, unit});
    };
    if (std::holds_alternative<SpatialJoint>(joint.kind)) {  // docs/spatial.md §2.6
      for (const char* c : {"Fx", "Fy", "Fz"}) add(c, true, "N");
      for (const char* c : {"Mx", "My", "Mz"}) add(c, true, "N*m");
      for (const char* c : {"Ff", "Fg", "Fh"}) add(c, false, "N");
      for (const char* c : {"Mf", "Mg", "Mh"}) add(c, false, "N*m");
      continue;
    }
    switch (joint.kind.index()) {
      case 0:  // revolute
        add("Fx", true, "N"), add("Fy", true, "N"), add("Fx_local", false, "N"),
            add("Fy_local", false, "N");
        break;
      case 1:  // prismatic
        add("Fx", true, "N"), add("Fy", true, "N"), add("M", true, "N*m"), add("N", false, "N");
        break;
      case 2:  // fixed
        add("Fx", true, "N"), add("Fy", true, "N"), add("M", true, "N*m"),
            add("Fx_local", false, "N"), add("Fy_local", false, "N");
        break;
      case 3:  // pin-in-slot
        add("Fx", true, "N"), add("Fy", true, "N"), add("N", false, "N");
        break;
      case 4:  // gear
        add("lambda", false, "N*m");
        break;
      default:  // distance
        add("Fx", true, "N"), add("Fy", true, "N"), add("T", false, "N");
        break;
    }
  }
  // Knife edges (nonholonomic rows after the joints'): the ground's lateral force on the body.
  for (size_t e = 0; e < model.knife_edges.size(); ++e) {
    const int ji = static_cast<int>(model.joints.size() + e);
    const std::string& name = model.knife_edges[e].name;
    out.push_back({name + ".Fx", ji, true, "N"});
    out.push_back({name + ".Fy", ji, true, "N"});
    out.push_back({name + ".N", ji, false, "N"});
  }
  // Rolling discs (after the knife edges, as their rows): the contact force of the ground on the
  // disc, world components and along t1, t2 (friction) and k (normal force).
  for (size_t d = 0; d < model.rolling_discs.size(); ++d) {
    const int index = static_cast<int>(model.joints.size() + model.knife_edges.size() + d);
    const std::string& name = model.rolling_discs[d].name;
    for (const char* c : {".Fx", ".Fy", ".Fz"}) out.push_back({name + c, index, true, "N"});
    for (const char* c : {".Ft1", ".Ft2", ".N"}) out.push_back({name + c, index, false, "N"});
  }
  return out;
}

// Forces and moments on the joint's first body from its second (docs/notation.md). The rows
// of λ are the generalized forces E λ: for rows written "first − second" (revolute, fixed x/y) λ is
// that force itself; for rows written "second − first" (slot normal, relative angle, rod) the
// force on the first body is −λ along the row's direction.
namespace {
void compute_reactions_at(const Model& model, const VecX& q, const Eigen::Ref<const VecX>& lambda,
                          std::vector<double>& out, const Eigen::Matrix2d* rotations) {
  out.clear();
  const VecX* none = nullptr;
  auto rot = [&](int body) -> Eigen::Matrix2d {
    return rotations && body != kGround ? rotations[body] : rotation(body_angle(model, body, q));
  };
  for (const Joint& joint : model.joints) {
    const int r = joint.row_offset;
    std::visit(
        [&](const auto& k) {
          using T = std::decay_t<decltype(k)>;
          if constexpr (std::is_same_v<T, Revolute> || std::is_same_v<T, Fixed>) {
            const Vec2 F(lambda(r), lambda(r + 1));
            // The joint's frame: its first body's, or its second's when the first is the
            // ground (the moving link's axes, where the ground's would repeat Fx, Fy).
            const int frame = k.pi.body != kGround ? k.pi.body : k.pj.body;
            const Vec2 local = rot(frame).transpose() * F;
            out.push_back(F.x());
            out.push_back(F.y());
            if constexpr (std::is_same_v<T, Fixed>) out.push_back(-lambda(r + 2));
            out.push_back(local.x());
            out.push_back(local.y());
          } else if constexpr (std::is_same_v<T, Prismatic> || std::is_same_v<T, PinInSlot>) {
            const Vec2 n = rot(k.pi.body) * perp(k.axis_local);
            const double normal = -lambda(r);
            out.push_back(normal * n.x());
            out.push_back(normal * n.y());
            if constexpr (std::is_same_v<T, Prismatic>) {
              // Moment about the joint's point pi on the first body (issue 10 item 8). The
              // normal row nᵀ(r_Pj − r_Pi) gives the first body the force N n acting at P_j
              // (its rotation entry is −λ(nᵀR'_i s_i + eᵀΔ), the moment of −λn applied at
              // P_i + Δ, Δ = r_Pj − r_Pi, e = R_i a) (M1); the angle row φ_j − φ_i the couple −λ_φ
              // (M2). About P_i: M = −λ_φ + Δ × (N n) = −λ_φ + N eᵀΔ, since Δ × n = eᵀΔ for
              // n = J e (M3).
              const Vec2 e = rot(k.pi.body) * k.axis_local;
              const Vec2 delta = detail::point_kinematics_at(model, k.pj, q, none, rotations).r -
                                 detail::point_kinematics_at(model, k.pi, q, none, rotations).r;
              out.push_back(-lambda(r + 1) + normal * e.dot(delta));  // (M3)
            }
            out.push_back(normal);
          } else if constexpr (std::is_same_v<T, GearPair>) {
            out.push_back(lambda(r));
          } else if constexpr (std::is_same_v<T, SpatialJoint>) {
            const SpatialWrench w =
                spatial_joint_reaction(model, k, q, lambda.segment(r, joint.rows()));
            for (const Vec3* v : {&w.force, &w.moment, &w.force_local, &w.moment_local})
              for (int a = 0; a < 3; ++a) out.push_back((*v)(a));
          } else {  // Distance: force on the first body = −λ d / L; tension along e = d/|d|
            const Vec2 d = detail::point_kinematics_at(model, k.pj, q, none, rotations).r -
                           detail::point_kinematics_at(model, k.pi, q, none, rotations).r;
            const Vec2 F = -lambda(r) * d / k.length;
            out.push_back(F.x());
            out.push_back(F.y());
            out.push_back(F.dot(d.normalized()));
          }
        },
        joint.kind);
  }
  // Knife edge: λ is the lateral force of the ground on the body along n = R(φ) perp(axis).
  for (const KnifeEdge& k : model.knife_edges) {
    const Vec2 n = rotation(body_angle(model, k.at.body, q)) * perp(k.axis_local);
    const double N = lambda(k.row_offset);
    out.push_back(N * n.x());
    out.push_back(N * n.y());
    out.push_back(N);
  }
  for (const RollingDisc& d : model.rolling_discs) {
    const Vec3 F = rolling_disc_contact_force(d, lambda.segment<3>(d.row_offset));
    for (int a = 0; a < 3; ++a) out.push_back(F(a));
    for (int a = 0; a < 3; ++a) out.push_back(lambda(d.row_offset + a));
  }
}
}  // namespace

void compute_reactions(const Model& model, const VecX& q, const Eigen::Ref<const VecX>& lambda,
                       std::vector<double>& out) {
  compute_reactions_at(model, q, lambda, out, nullptr);
}

void compute_reactions(const Model& model, const VecX& q, const BodyPoses& rotations,
                       const Eigen::Ref<const VecX>& lambda, std::vector<double>& out) {
  compute_reactions_at(model, q, lambda, out, rotations.table().data());
}

}  // namespace orthomech

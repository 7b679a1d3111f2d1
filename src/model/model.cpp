#include "orthomech/model/model.hpp"

#include <stdexcept>

#include "orthomech/check.hpp"
#include "orthomech/constraints/constraint_system.hpp"
#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/general_system.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

int Joint::rows() const {
  return std::visit(
      [](const auto& j) -> int {
        using T = std::decay_t<decltype(j)>;
        if constexpr (std::is_same_v<T, Revolute> || std::is_same_v<T, Prismatic>) return 2;
        if constexpr (std::is_same_v<T, Fixed>) return 3;
        if constexpr (std::is_same_v<T, SpatialJoint>) return spatial_joint_spec(j.type).rows;
        return 1;  // PinInSlot, GearPair, Distance
      },
      kind);
}

std::string Joint::type_name() const {
  if (const auto* s = std::get_if<SpatialJoint>(&kind)) return spatial_joint_spec(s->type).type;
  static const char* names[] = {"revolute",    "prismatic", "fixed",
                                "pin-in-slot", "gear",      "distance"};
  return names[kind.index()];
}

std::vector<std::string> Joint::component_names() const {
  if (const auto* s = std::get_if<SpatialJoint>(&kind)) {
    const SpatialJointSpec& spec = spatial_joint_spec(s->type);
    std::vector<std::string> names;
    names.reserve(static_cast<size_t>(spec.rows));
    for (int k = 0; k < spec.rows; ++k) names.emplace_back(spec.row[static_cast<size_t>(k)].name);
    return names;
  }
  switch (kind.index()) {
    case 0:
      return {"x", "y"};
    case 1:
      return {"n", "angle"};
    case 2:
      return {"x", "y", "angle"};
    case 3:
      return {"n"};
    case 4:
      return {"ratio"};
    default:
      return {"length"};
  }
}

int Model::find_body(const std::string& body) const {
  if (body == "ground") return kGround;
  for (size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == body) return static_cast<int>(i);
  return -2;
}

int Model::find_joint(const std::string& joint) const {
  for (size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == joint) return static_cast<int>(i);
  return -1;
}

int Model::find_measure(const std::string& measure) const {
  for (size_t i = 0; i < measures.size(); ++i)
    if (measures[i].name == measure) return static_cast<int>(i);
  return -1;
}

VecX Model::design_q() const { return free_system(*this).design_q(*this); }

std::string Model::constraint_row_name(int row) const {
  return constraint_system(*this).row_name(*this, row);
}

void finalize_model(Model& model) {
  if (model.general) {
    if (!model.bodies.empty() || !model.joints.empty() || !model.knife_edges.empty() ||
        !model.rolling_discs.empty() || !model.loads.empty() || !model.measures.empty() ||
        !model.drivers.empty())
      throw std::invalid_argument(
          "finalize_model: a general system has no bodies, joints, loads, measures or drivers");
    model.nq = model.n = model.general->n;
    model.nc = model.general->nc;
    return;
  }
  int q_off = 0, u_off = 0;
  for (Body& b : model.bodies) {
    if ((b.kind == BodyKind::spatial) != (model.dimension == 3))
      throw std::invalid_argument("finalize_model: body '" + b.name +
                                  "' does not match the model's dimension (all planar or all "
                                  "spatial)");
    b.q_offset = q_off;
    b.u_offset = u_off;
    q_off += b.nq();
    u_off += b.nu();
  }
  model.nq = q_off;
  model.n = u_off;
  int row = 0;
  for (Joint& j : model.joints) {
    j.row_offset = row;
    row += j.rows();
  }
  for (KnifeEdge& k : model.knife_edges) k.row_offset = row++;
  for (RollingDisc& d : model.rolling_discs) {
    d.row_offset = row;
    row += 3;
  }
  model.nc = row;
  const int nb = static_cast<int>(model.bodies.size());
  auto check_body = [nb](int b) {
    check_argument(b >= kGround && b < nb, "finalize_model", "model",
                   "has a body index out of range");
  };
  for (const KnifeEdge& k : model.knife_edges) {
    check_body(k.at.body);
    if (k.at.body == kGround ||
        model.bodies[static_cast<size_t>(k.at.body)].kind != BodyKind::rigid)
      throw std::invalid_argument("finalize_model: a knife edge needs a rigid moving body");
  }
  for (const RollingDisc& d : model.rolling_discs) {
    check_body(d.body);
    if (d.body == kGround || model.bodies[static_cast<size_t>(d.body)].kind != BodyKind::spatial)
      throw std::invalid_argument("finalize_model: a rolling disc needs a spatial moving body");
    if (!(d.radius > 0.0))
      throw std::invalid_argument("finalize_model: a rolling disc needs a positive radius");
  }
  for (const Joint& j : model.joints) {
    std::visit(
        [&](const auto& k) {
          using T = std::decay_t<decltype(k)>;
          if constexpr (std::is_same_v<T, SpatialJoint>) {
            if (model.dimension != 3)
              throw std::invalid_argument("finalize_model: spatial joint in a planar model");
            check_body(k.pi.body);
            check_body(k.pj.body);
          } else if constexpr (std::is_same_v<T, GearPair>) {
            check_body(k.bi);
            check_body(k.bj);
            check_body(k.carrier);
          } else {
            if (model.dimension != 2)
              throw std::invalid_argument("finalize_model: planar joint in a spatial model");
            check_body(k.pi.body);
            check_body(k.pj.body);
          }
        },
        j.kind);
  }
}

Model make_general_model(std::string name, GeneralSystem system) {
  const auto need = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("make_general_model: ") + what);
  };
  need(system.n > 0 && system.nc >= 0, "n must be positive and nc non-negative");
  need(system.mass && system.mass_rate && system.forces && system.residual && system.jacobian &&
           system.jacobian_rate,
       "every function (mass, mass_rate, forces, residual, jacobian, jacobian_rate) is needed");
  need(system.q0.size() == system.n, "q0 must have n entries");
  // Default names q1…, g1… (appended: GCC 12 warns falsely on "q" + std::string).
  const auto numbered = [](char prefix, int k) {
    std::string label(1, prefix);
    label += std::to_string(k + 1);
    return label;
  };
  if (system.coordinates.empty())
    for (int k = 0; k < system.n; ++k) system.coordinates.push_back(numbered('q', k));
  if (system.rows.empty())
    for (int k = 0; k < system.nc; ++k) system.rows.push_back(numbered('g', k));
  need(static_cast<int>(system.coordinates.size()) == system.n, "n coordinate names");
  need(static_cast<int>(system.rows.size()) == system.nc, "nc row names");
  Model model;
  model.name = std::move(name);
  model.general = std::make_shared<const GeneralSystem>(std::move(system));
  finalize_model(model);
  return model;
}

}  // namespace orthomech

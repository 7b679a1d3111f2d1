// The spatial file format (`dimension: 3`, docs/file-format.md "Spatial mechanisms"): the model
// the reader builds is checked against an independent computation written here (rotation
// matrices by explicit formulas, points and joint frames from the file's numbers, the RSSR
// closed form of docs/spatial.md (M1)), and every bundled spatial mechanism against its stated
// mobility (docs/spatial.md §4).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"
#include "support/spatial_oracles.hpp"

namespace orthomech {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Mat3 rx(double a) {
  Mat3 R;
  R << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  return R;
}
Mat3 ry(double a) {
  Mat3 R;
  R << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return R;
}
Mat3 rz(double a) {
  Mat3 R;
  R << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return R;
}

// The rotation whose body x, z axes are given in world (x kept, z made perpendicular to it).
Mat3 from_x_z(const Vec3& x_in, const Vec3& z_in) {
  const Vec3 x = x_in.normalized();
  const Vec3 z = (z_in - z_in.dot(x) * x).normalized();
  Mat3 R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return R;
}

Mat3 design_R(const Model& m, const std::string& body) {
  return rotation_matrix(
      m.bodies[static_cast<size_t>(m.find_body(body))].spatial.design_orientation);
}
const SpatialJoint& spatial_joint(const Model& m, const std::string& name) {
  return std::get<SpatialJoint>(m.joints[static_cast<size_t>(m.find_joint(name))].kind);
}
double measure(const Model& m, const std::string& name, const VecX& q) {
  return evaluate_measure(m, m.measures[static_cast<size_t>(m.find_measure(name))], q, nullptr,
                          nullptr);
}
double max_residual(const Model& m, const VecX& q) {
  VecX f(m.nc);
  compute_constraint_residual(m, q, f);
  return f.cwiseAbs().maxCoeff();
}

// RSSR closed form (docs/spatial.md (M1)), SI: φ(θ) on the branch of the file.
using test::rssr_rocker_angle;  // (M1)

// ---- RSSR (mechanisms/rssr.yaml = docs/spatial.md §5) -------------------------------------------
TEST(SpatialFile, RssrBodiesPointsAndFramesMatchAnIndependentComputation) {
  const Model m = load_mechanism(test::source_path("mechanisms/rssr.yaml"));
  ASSERT_EQ(m.dimension, 3);
  ASSERT_EQ(m.bodies.size(), 3u);
  for (const Body& b : m.bodies) EXPECT_EQ(b.kind, BodyKind::spatial);
  // Poses: crank about z by 30°; coupler, rocker from their {x, z} axes; positions in m.
  const Mat3 Rc = rz(30 * kDeg);
  const Mat3 Rcp =
      from_x_z(Vec3(0.50808919, -0.56096537, 0.65357725), Vec3(0, -0.75882256, -0.65129742));
  const Mat3 Rr = from_x_z(Vec3(0, -0.92802728, 0.37251223), Vec3(1, 0, 0));
  EXPECT_LT((design_R(m, "crank") - Rc).norm(), 1e-14);
  EXPECT_LT((design_R(m, "coupler") - Rcp).norm(), 1e-14);
  EXPECT_LT((design_R(m, "rocker") - Rr).norm(), 1e-14);
  const auto& coupler = m.bodies[1].spatial;
  EXPECT_LT((coupler.design_position - Vec3(0.08660254037844386, 0.05, 0)).norm(), 1e-15);
  EXPECT_LT((coupler.com_local - Vec3(0.21, 0, 0)).norm(), 1e-15);
  // Inertia kg·mm² → kg·m².
  EXPECT_NEAR(coupler.inertia(1, 1), 7350e-6, 1e-18);
  EXPECT_NEAR(coupler.inertia(0, 0), 1e-6, 1e-20);
  EXPECT_EQ(coupler.inertia(0, 1), 0.0);
  // Point offsets from the com: coupler.B = (420, 0, 0) mm − com (210, 0, 0) mm.
  const SpatialJoint& B = spatial_joint(m, "B");
  EXPECT_EQ(B.type, SpatialJointType::universal);
  EXPECT_LT((B.pi.s - Vec3(0.21, 0, 0)).norm(), 1e-15);
  EXPECT_LT((B.pj.s - Vec3(0.1, 0, 0)).norm(), 1e-15);  // rocker.B (200) − com (100)
  // Universal: pin 1 = coupler z in the coupler's frame; pin 2 = rocker z in the rocker's frame.
  EXPECT_LT((B.frame_i.col(0) - Vec3::UnitZ()).norm(), 1e-7);
  EXPECT_LT((B.frame_j.col(1) - Vec3::UnitZ()).norm(), 1e-7);
  // One world frame at the design pose in both bodies.
  EXPECT_LT((Rcp * B.frame_i - Rr * B.frame_j).norm(), 1e-14);
  // Crank revolute A0 (ground first): f = world x, h = world z; in the crank: Rcᵀ A.
  const SpatialJoint& A0 = spatial_joint(m, "A0");
  EXPECT_LT((A0.frame_i - Mat3::Identity()).norm(), 1e-14);
  EXPECT_LT((A0.frame_j - Rc.transpose()).norm(), 1e-14);
  EXPECT_LT((A0.ref_j - Vec3::UnitX()).norm(), 1e-14);  // crank x, least aligned with z
  EXPECT_LT((A0.pi.s - Vec3::Zero()).norm(), 1e-15);
  EXPECT_LT((A0.pj.s - Vec3(-0.05, 0, 0)).norm(), 1e-15);  // crank.O − com
  // Rocker revolute B0 (axis world x): f = world y (x is the axis), g = z, h = x.
  const SpatialJoint& B0 = spatial_joint(m, "B0");
  Mat3 A;
  A << Vec3::UnitY(), Vec3::UnitZ(), Vec3::UnitX();
  EXPECT_LT((B0.frame_i - A).norm(), 1e-14);
  EXPECT_LT((B0.frame_j - Rr.transpose() * A).norm(), 1e-14);
  EXPECT_LT((B0.ref_j - Vec3::UnitX()).norm(), 1e-14);  // rocker x: least aligned with rocker z
}

TEST(SpatialFile, RssrClosesAtTheDesignPoseAndItsJointMeasuresReadTheClosedFormAngles) {
  const Model m = load_mechanism(test::source_path("mechanisms/rssr.yaml"));
  const VecX q = m.design_q();
  // 8-digit orientation axes: the coupler end B is off by ~420 mm × 1e-8.
  EXPECT_LT(max_residual(m, q), 2e-8);
  EXPECT_NEAR(measure(m, "crank_angle", q), 30 * kDeg, 1e-14);
  EXPECT_NEAR(measure(m, "rocker_angle", q), 158.12936317866155 * kDeg, 1e-7);
  // Closed to rounding with the crank held at 30°: the rocker angle is (M1)'s to 1e-10 rad.
  VecX qa = q;
  PositionOptions hold;
  hold.locked_joint = m.find_joint("A0");
  hold.locked_value = 30 * kDeg;
  ASSERT_EQ(project_positions(m, qa, hold).status, SolveStatus::converged);
  EXPECT_NEAR(measure(m, "rocker_angle", qa), rssr_rocker_angle(30 * kDeg), 1e-10);
  EXPECT_NEAR(rssr_rocker_angle(30 * kDeg), 158.12936317866155 * kDeg, 1e-12);
}

// ---- every bundled spatial mechanism ----------------------------------------------------------
struct Expected {
  const char* file;
  double residual;  // max |f| at the design pose, SI
  int dof, redundant, rank;
};

TEST(SpatialFile, BundledMechanismsCloseAndHaveTheirMobility) {
  const Expected cases[] = {
      {"rssr.yaml", 2e-8, 1, 0, 17},
      {"bennett.yaml", 1e-14, 1, 3, 17},
      {"bricard.yaml", 1e-14, 1, 1, 29},
      {"hooke-joint.yaml", 1e-14, 1, 3, 11},
      {"spatial-slider-crank.yaml", 1e-14, 1, 0, 17},
      {"heavy-top.yaml", 1e-14, 3, 0, 3},
      {"crank-rocker-3d.yaml", 1e-14, 1, 3, 17},
  };
  for (const Expected& e : cases) {
    SCOPED_TRACE(e.file);
    const Model m = load_mechanism(test::source_path(std::string("mechanisms/") + e.file));
    EXPECT_EQ(m.dimension, 3);
    EXPECT_TRUE(m.warnings.empty()) << m.warnings.front();
    VecX q = m.design_q();
    EXPECT_LT(max_residual(m, q), e.residual);
    ASSERT_EQ(project_positions(m, q).status, SolveStatus::converged);
    const Mobility mob = compute_mobility(m, q);
    EXPECT_EQ(mob.dof, e.dof);
    EXPECT_EQ(mob.rank, e.rank);
    EXPECT_EQ(static_cast<int>(mob.redundant.size()), e.redundant);
    EXPECT_EQ(mob.grubler, m.n - m.nc);
  }
}

// The files' joint measures read the angles their headers state (docs/spatial.md §4).
TEST(SpatialFile, BundledMechanismsMeasuresReadTheirDesignAngles) {
  {
    const Model m = load_mechanism(test::source_path("mechanisms/bennett.yaml"));
    const VecX q = m.design_q();
    EXPECT_NEAR(measure(m, "theta1", q), 75 * kDeg, 1e-14);
    EXPECT_NEAR(measure(m, "theta2", q), 148.6240189537 * kDeg, 1e-11);
    // Bennett's closure tan(θ1/2) tan(θ2/2) = sin 45°/sin 15°.
    EXPECT_NEAR(std::tan(measure(m, "theta1", q) / 2) * std::tan(measure(m, "theta2", q) / 2),
                std::sin(45 * kDeg) / std::sin(15 * kDeg), 1e-12);
  }
  {
    const Model m = load_mechanism(test::source_path("mechanisms/spatial-slider-crank.yaml"));
    const VecX q = m.design_q();
    EXPECT_NEAR(measure(m, "crank_angle", q), 90 * kDeg, 1e-14);
    EXPECT_NEAR(measure(m, "slider_x", q), 0.2, 1e-14);  // (M2) at φ = 90°
  }
  {
    const Model m = load_mechanism(test::source_path("mechanisms/hooke-joint.yaml"));
    const VecX q = m.design_q();
    EXPECT_NEAR(measure(m, "theta1", q), 0.0, 1e-14);
    EXPECT_NEAR(measure(m, "theta2", q), 0.0, 1e-14);
  }
  {
    const Model m = load_mechanism(test::source_path("mechanisms/crank-rocker-3d.yaml"));
    const VecX q = m.design_q();
    EXPECT_NEAR(measure(m, "crank_angle", q), 60 * kDeg, 1e-14);
    EXPECT_NEAR(measure(m, "rocker_angle", q), 71.79755360961532 * kDeg, 1e-14);
  }
  {
    const Model m = load_mechanism(test::source_path("mechanisms/heavy-top.yaml"));
    EXPECT_NEAR(measure(m, "nutation", m.design_q()), 30 * kDeg, 1e-14);
  }
}

TEST(SpatialFile, InfoJsonWorksOnEveryBundledSpatialMechanism) {
  const std::pair<const char*, int> files[] = {{"rssr", 1},
                                               {"bennett", 1},
                                               {"bricard", 1},
                                               {"hooke-joint", 1},
                                               {"spatial-slider-crank", 1},
                                               {"heavy-top", 3},
                                               {"crank-rocker-3d", 1}};
  for (const auto& [f, dof] : files) {
    const auto r = test::run_cli(
        {"info", test::source_path(std::string("mechanisms/") + f + ".yaml"), "--json"});
    ASSERT_EQ(r.status, 0) << f << "\n" << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["dimension"], 3) << f;
    EXPECT_EQ(j["dof"], dof) << f;
    EXPECT_EQ(j["assembly"]["status"], "converged") << f;
    for (const auto& b : j["bodies"]) {
      EXPECT_EQ(b["type"], "spatial") << f;
      ASSERT_EQ(b["inertia"].size(), 3u) << f;
      EXPECT_EQ(b["inertia"][0].size(), 3u) << f;
    }
  }
}

// Every joint type, load and measure of the format, read into the model types: the type, the
// one world frame in both bodies (R_i F_i = R_j F_j, h = R_i axis), pitch, lengths, load and
// measure fields.
const char* kEverything = R"(orthomech: 1
dimension: 3
units: {length: m, angle: deg}
ground:
  points: {O: [0, 0, 0], P: [0, 0, 2]}
bodies:
  - name: a
    mass: 2
    inertia: [0.1, 0.2, 0.25]
    pose: {position: [0, 0, 0], orientation: {axis: [1, 1, 1], angle: 40}}
    points: {O: [0, 0, 0], T: [0.3, 0, 0]}
  - name: b
    mass: 1
    inertia: [0.1, 0.1, 0.1]
    pose: {position: [0, 0, 0], orientation: {euler: [10, 20, 30], sequence: xyz}}
  - name: c
    mass: 1
    inertia: [0.1, 0.1, 0.1]
    pose: {position: [0, 0, 0], orientation: {axis: [1, 1, 1], angle: 40}}
joints:
  - {name: j0, type: spherical, connects: [ground.O, a.O]}
  - {name: j1, type: revolute, connects: [a.O, b.origin], axis: [0, 3, 4]}
  - {name: j2, type: cylindrical, connects: [a.O, b.origin], axis: [1, 0, 0], limits: [-90, 90]}
  - {name: j3, type: prismatic, connects: [ground.O, b.origin], axis: [0, 0, 2], limits: [-1, 1]}
  - {name: j4, type: fixed, connects: [a.O, b.origin]}
  - {name: j5, type: universal, connects: [a.O, c.origin], axes: [[0, 0, 1], [0, 1, 0]]}
  - {name: j6, type: planar, connects: [ground.O, a.O], axis: [0, 0, 1]}
  - {name: j7, type: point-on-line, connects: [ground.O, a.O], axis: [1, 1, 0]}
  - {name: j8, type: point-on-plane, connects: [b.origin, a.O], axis: [0, 1, 0]}
  - {name: j9, type: distance, connects: [ground.P, a.O]}
  - {name: j10, type: screw, connects: [ground.O, b.origin], axis: [0, 0, 1], pitch: 0.004}
  - {name: j11, type: distance, connects: [ground.P, b.origin], length: 3}
loads:
  - {name: g, type: gravity}
  - {name: F, type: force, point: a.T, force: [1, 2, 3], frame: body}
  - {name: T, type: torque, body: b, torque: [0, 0, 5]}
  - {name: k, type: spring-damper, connects: [ground.P, a.T], stiffness: 10, free_length: 1, damping: 2}
  - {name: r, type: rotary-spring-damper, joint: j1, stiffness: 3, free_angle: 90, damping: 0.5}
measures:
  - {name: m0, type: joint, joint: j2}
  - {name: m1, type: joint, joint: j3, derivative: 1}
  - {name: m2, type: point, point: a.T, component: z}
  - {name: m3, type: distance, points: [ground.P, a.T]}
  - {name: m4, type: angle, between: [{body: a, vector: [0, 0, 2]}, {body: ground, vector: [0, 0, 1]}]}
drivers:
  - {name: d0, joint: j2, speed: 30 rpm}
  - {name: d1, joint: j3, speed: 0.5}
  - {name: d2, joint: j10, speed: 1 rad/s}
design_positions:
  - {name: p, inputs: {j10: 45, j3: 0.5}}
)";

TEST(SpatialFile, EveryJointTypeLoadAndMeasureIsRead) {
  const Model m = parse_mechanism(kEverything, "everything.yaml");
  using T = SpatialJointType;
  const T types[] = {T::spherical,      T::revolute,  T::cylindrical, T::prismatic,
                     T::fixed,          T::universal, T::planar,      T::point_on_line,
                     T::point_on_plane, T::distance,  T::screw,       T::distance};
  const int rows[] = {3, 5, 4, 5, 6, 4, 3, 2, 1, 1, 5, 1};
  ASSERT_EQ(m.joints.size(), 12u);
  EXPECT_EQ(m.nc, 3 + 5 + 4 + 5 + 6 + 4 + 3 + 2 + 1 + 1 + 5 + 1);
  const Mat3 Ra = Eigen::AngleAxisd(40 * kDeg, Vec3(1, 1, 1).normalized()).toRotationMatrix();
  const Mat3 Rb = rx(10 * kDeg) * ry(20 * kDeg) * rz(30 * kDeg);
  EXPECT_LT((design_R(m, "a") - Ra).norm(), 1e-14);
  EXPECT_LT((design_R(m, "b") - Rb).norm(), 1e-14);
  const auto R = [&](int body) {
    return body == kGround ? Mat3(Mat3::Identity()) : body == 1 ? Rb : Ra;  // c is turned as a
  };
  for (size_t k = 0; k < m.joints.size(); ++k) {
    SCOPED_TRACE(m.joints[k].name);
    const auto& j = std::get<SpatialJoint>(m.joints[k].kind);
    EXPECT_EQ(j.type, types[k]);
    EXPECT_EQ(m.joints[k].rows(), rows[k]);
    const Mat3 Ai = R(j.pi.body) * j.frame_i, Aj = R(j.pj.body) * j.frame_j;
    EXPECT_LT((Ai - Aj).norm(), 1e-14);                                 // one world frame
    EXPECT_LT((Ai.transpose() * Ai - Mat3::Identity()).norm(), 1e-14);  // orthonormal
    EXPECT_NEAR(Ai.determinant(), 1.0, 1e-14);                          // right-handed
    // ref_j: unit, perpendicular to the axis, in body j's frame.
    EXPECT_NEAR(j.ref_j.norm(), 1.0, 1e-14);
    EXPECT_NEAR(j.ref_j.dot(j.frame_j.col(2)), 0.0, 1e-14);
  }
  const auto joint = [&](int k) {
    return std::get<SpatialJoint>(m.joints[static_cast<size_t>(k)].kind);
  };
  EXPECT_LT((Ra * joint(1).frame_i.col(2) - Ra * Vec3(0, 0.6, 0.8)).norm(), 1e-14);
  EXPECT_LT((joint(3).frame_i.col(2) - Vec3::UnitZ()).norm(), 1e-14);  // ground: world
  EXPECT_LT((joint(7).frame_i.col(2) - Vec3(1, 1, 0).normalized()).norm(), 1e-14);
  // Universal: pin 1 = a's z, pin 2 = c's y (world), the frame's f and g.
  EXPECT_LT((Ra * joint(5).frame_i.col(0) - Ra.col(2)).norm(), 1e-14);
  EXPECT_LT((Ra * joint(5).frame_j.col(1) - Ra.col(1)).norm(), 1e-14);
  // Fixed without an axis: body 1's axes.
  EXPECT_LT((joint(4).frame_i - Mat3::Identity()).norm(), 1e-14);
  EXPECT_EQ(joint(10).pitch, 0.004);
  EXPECT_NEAR(joint(9).length, 2.0, 1e-14);  // from the design pose
  EXPECT_EQ(joint(11).length, 3.0);
  ASSERT_TRUE(m.joints[2].limits.has_value());
  EXPECT_NEAR((*m.joints[2].limits)(1), 90 * kDeg, 1e-14);
  EXPECT_EQ((*m.joints[3].limits)(0), -1.0);
  // Only j11's points miss (2 m apart, length 3): one warning.
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_NE(m.warnings[0].find("joint 'j11': its points are 2 m apart, the length is 3 m"),
            std::string::npos)
      << m.warnings[0];
  // Loads.
  ASSERT_EQ(m.loads.size(), 5u);
  EXPECT_EQ(std::get<SpatialGravity>(m.loads[0].kind).g, Vec3(0, 0, -9.81));
  const auto& F = std::get<SpatialPointForce>(m.loads[1].kind);
  EXPECT_TRUE(F.body_fixed);
  EXPECT_EQ(F.force, Vec3(1, 2, 3));
  EXPECT_EQ(F.at.body, 0);
  EXPECT_EQ(F.at.s, Vec3(0.3, 0, 0));
  const auto& Tq = std::get<SpatialTorque>(m.loads[2].kind);
  EXPECT_FALSE(Tq.body_fixed);
  EXPECT_EQ(Tq.body, 1);
  EXPECT_EQ(Tq.torque, Vec3(0, 0, 5));
  const auto& sd = std::get<SpatialSpringDamper>(m.loads[3].kind);
  EXPECT_EQ(sd.pi.s, Vec3(0, 0, 2));
  EXPECT_EQ(sd.stiffness, 10.0);
  EXPECT_EQ(sd.damping, 2.0);
  const auto& rs = std::get<JointSpringDamper>(m.loads[4].kind);
  EXPECT_EQ(rs.joint, 1);
  EXPECT_NEAR(rs.free_angle, 90 * kDeg, 1e-14);
  EXPECT_NEAR(rs.stiffness, 3.0 / kDeg, 1e-9);  // N·m per degree in the file
  // Measures: kinds, units; values at the design pose against explicit formulas.
  EXPECT_EQ(m.measures[0].unit, "rad");
  EXPECT_EQ(m.measures[1].unit, "m/s");
  EXPECT_EQ(m.measures[2].unit, "m");
  EXPECT_EQ(m.measures[4].unit, "rad");
  const VecX q = m.design_q();
  EXPECT_NEAR(measure(m, "m2", q), (Ra * Vec3(0.3, 0, 0)).z(), 1e-14);
  EXPECT_NEAR(measure(m, "m3", q), (Ra * Vec3(0.3, 0, 0) - Vec3(0, 0, 2)).norm(), 1e-14);
  EXPECT_NEAR(measure(m, "m4", q), std::acos(Ra(2, 2)), 1e-12);
  // Drivers: angular on cylindrical and screw, linear on prismatic; inputs in SI.
  ASSERT_EQ(m.drivers.size(), 3u);
  EXPECT_NEAR(m.drivers[0].speed, std::numbers::pi, 1e-14);  // 30 rpm
  EXPECT_EQ(m.drivers[1].speed, 0.5);
  EXPECT_EQ(m.drivers[2].speed, 1.0);
  ASSERT_EQ(m.design_positions[0].inputs.size(), 2u);
  EXPECT_NEAR(m.design_positions[0].inputs[0].second, 45 * kDeg, 1e-14);
  EXPECT_EQ(m.design_positions[0].inputs[1].second, 0.5);
}

// The RSSR file's frames give the closed form (M1) at every crank angle (crank held, the rest
// closed by Gauss–Newton): the joint measures are the closed form's θ and φ.
TEST(SpatialFile, RssrRockerAngleFollowsTheClosedFormAroundTheTurn) {
  const Model m = load_mechanism(test::source_path("mechanisms/rssr.yaml"));
  PositionOptions hold;
  hold.locked_joint = m.find_joint("A0");
  const double published[] = {135.1704559498, 208.8717849220, 232.6552556460, 155.7416825678};
  // 5° steps from the design pose's 30° up to 175° and down to −175° (the joint angle is in
  // (−180°, 180°]; the lock of project_positions does not wrap across ±180°).
  for (const int step : {5, -5}) {
    VecX q = m.design_q();
    for (int degrees = 30 + step; degrees >= -175 && degrees <= 175; degrees += step) {
      const double theta = degrees * kDeg;
      hold.locked_value = theta;
      ASSERT_EQ(project_positions(m, q, hold).status, SolveStatus::converged) << degrees;
      EXPECT_NEAR(measure(m, "crank_angle", q), theta, 1e-12);
      EXPECT_NEAR(std::remainder(measure(m, "rocker_angle", q) - rssr_rocker_angle(theta),
                                 2 * std::numbers::pi),
                  0.0, 1e-10)
          << "theta " << degrees;
      if (degrees % 90 == 0) {
        EXPECT_NEAR(std::remainder(
                        rssr_rocker_angle(theta) - published[((degrees + 360) % 360) / 90] * kDeg,
                        2 * std::numbers::pi),
                    0.0, 1e-11);
      }
    }
  }
}

// Velocities of the bundled files against their closed forms: u solves Eᵀu = 0 with the given
// rates of measures (least squares on [Eᵀ; d_k] u = [0; rate_k], exact when consistent).
VecX velocity_with_rates(const Model& m, const VecX& q,
                         const std::vector<std::pair<std::string, double>>& rates) {
  MatX Et(m.nc, m.n);
  compute_constraint_jacobian(m, q, Et);
  MatX A(m.nc + static_cast<int>(rates.size()), m.n);
  VecX b = VecX::Zero(A.rows());
  A.topRows(m.nc) = Et;
  for (size_t k = 0; k < rates.size(); ++k) {
    VecX d(m.n);
    const Measure& me = m.measures[static_cast<size_t>(m.find_measure(rates[k].first))];
    (void)compute_scalar(m, me.kind, q, nullptr, d);
    A.row(m.nc + static_cast<int>(k)) = d.transpose();
    b(m.nc + static_cast<int>(k)) = rates[k].second;
  }
  return A.completeOrthogonalDecomposition().solve(b);
}
double rate(const Model& m, const std::string& name, const VecX& q, const VecX& u) {
  const Measure& me = m.measures[static_cast<size_t>(m.find_measure(name))];
  return compute_scalar(m, me.kind, q, &u).rate;
}

TEST(SpatialFile, HookeJointVelocityRatioIsTheClosedForm) {
  const Model m = load_mechanism(test::source_path("mechanisms/hooke-joint.yaml"));
  const double beta = 30 * kDeg;
  PositionOptions hold;
  hold.locked_joint = m.find_joint("R1");
  VecX q = m.design_q();
  for (int degrees = 0; degrees <= 85; degrees += 5) {
    const double t1 = degrees * kDeg;
    hold.locked_value = t1;
    ASSERT_EQ(project_positions(m, q, hold).status, SolveStatus::converged) << degrees;
    // θ2 of pin 2 from its design direction: tan θ2 = cos β tan θ1, whose derivative is the
    // ratio below (docs/spatial.md §4.5: the plan's tan θ1/cos β is the relation with the shafts
    // exchanged).
    EXPECT_NEAR(std::tan(measure(m, "theta2", q)), std::cos(beta) * std::tan(t1), 1e-10) << degrees;
    const VecX u = velocity_with_rates(m, q, {{"theta1", 1.0}});
    const double ratio = std::cos(beta) / (1 - std::pow(std::sin(beta) * std::sin(t1), 2));
    EXPECT_NEAR(rate(m, "theta2", q, u), ratio, 1e-10) << degrees;
  }
}

// (M2): x_C(φ) over a crank turn, and ẋ_C = 0.24 m/s at φ = 90° with φ̇ = 6 rad/s (the file's
// `initial` rate).
TEST(SpatialFile, SpatialSliderCrankFollowsM2) {
  const Model m = load_mechanism(test::source_path("mechanisms/spatial-slider-crank.yaml"));
  const auto xc = [](double phi) {
    return std::sqrt(0.09 - std::pow(0.1 + 0.08 * std::cos(phi), 2) -
                     std::pow(0.12 + 0.08 * std::sin(phi), 2));
  };
  VecX q = m.design_q();
  const VecX u0 = velocity_with_rates(m, q, {{"crank_angle", 6.0}});
  EXPECT_NEAR(rate(m, "slider_x", q, u0), 0.24, 1e-12);
  ASSERT_EQ(m.initial.rates.size(), 1u);
  EXPECT_EQ(m.initial.rates[0].rate, 6.0);
  PositionOptions hold;
  hold.locked_joint = m.find_joint("A0");
  for (int degrees = 95; degrees <= 175; degrees += 5) {
    hold.locked_value = degrees * kDeg;
    ASSERT_EQ(project_positions(m, q, hold).status, SolveStatus::converged) << degrees;
    EXPECT_NEAR(measure(m, "slider_x", q), xc(degrees * kDeg), 1e-10) << degrees;
  }
}

// heavy-top.yaml's `initial` rates give the slow steady precession of (M3): the body's world
// angular velocity w = Ω z + (ω3 − Ω cos θ) axis, Ω (C ω3 − A_O Ω cos θ) = m g l.
TEST(SpatialFile, HeavyTopInitialRatesAreTheSteadyPrecession) {
  const Model m = load_mechanism(test::source_path("mechanisms/heavy-top.yaml"));
  const double C = 0.004, AO = 0.002 + 0.01, w3 = 100, th = 30 * kDeg, mgl = 9.81 * 0.1;
  const double Om =
      (C * w3 - std::sqrt(C * C * w3 * w3 - 4 * AO * mgl * std::cos(th))) / (2 * AO * std::cos(th));
  EXPECT_NEAR(Om * (C * w3 - AO * Om * std::cos(th)), mgl, 1e-12);
  const Vec3 axis(std::sin(th), 0, std::cos(th));
  const Vec3 w = Om * Vec3::UnitZ() + (w3 - Om * std::cos(th)) * axis;
  std::vector<std::pair<std::string, double>> rates;
  for (const InitialRateSpec& r : m.initial.rates)
    rates.emplace_back(m.measures[static_cast<size_t>(r.measure)].name, r.rate);
  ASSERT_EQ(rates.size(), 3u);
  const VecX q = m.design_q();
  const VecX u = velocity_with_rates(m, q, rates);
  const Vec3 w_world = design_R(m, "top") * u.segment<3>(3);
  EXPECT_LT((w_world - w).norm(), 1e-10 * w.norm());
}

// Bennett's closure tan(θ1/2) tan(θ2/2) = sin((β+α)/2)/sin((β−α)/2) at the angles of
// docs/spatial.md §4.2. The loop is closed by a minimum-norm Gauss–Newton written here (least
// squares on all rows and the held crank: the redundant rows stay consistent), from the
// design pose.
TEST(SpatialFile, BennettFollowsItsClosure) {
  const Model m = load_mechanism(test::source_path("mechanisms/bennett.yaml"));
  const MeasureKind crank = JointCoordinate{m.find_joint("J1")};
  const std::pair<int, double> published[] = {
      {20, 172.6144863489}, {75, 148.6240189537}, {140, 89.6773892272}};
  for (const int step : {5, -5}) {
    VecX q = m.design_q();
    for (int degrees = 75 + step; degrees >= 10 && degrees <= 170; degrees += step) {
      const double t1 = degrees * kDeg;
      for (int it = 0; it < 30; ++it) {
        MatX Et(m.nc, m.n), A(m.nc + 1, m.n);
        VecX f(m.nc), b(m.nc + 1), d(m.n);
        compute_constraint_residual(m, q, f);
        compute_constraint_jacobian(m, q, Et);
        const double s = compute_scalar(m, crank, q, nullptr, d).value;
        A << Et, d.transpose();
        b << f, s - t1;
        if (b.cwiseAbs().maxCoeff() < 1e-14) break;
        const VecX du = A.completeOrthogonalDecomposition().solve(b);
        integrate_positions(m, q, du, -1.0);
      }
      EXPECT_LT(max_residual(m, q), 1e-13) << degrees;
      EXPECT_NEAR(measure(m, "theta1", q), t1, 1e-13);
      const double t2 = measure(m, "theta2", q);
      EXPECT_NEAR(std::tan(t1 / 2) * std::tan(t2 / 2), std::sin(45 * kDeg) / std::sin(15 * kDeg),
                  1e-9)
          << degrees;
      for (const auto& [a, expected] : published) {
        if (a == degrees) {
          EXPECT_NEAR(t2, expected * kDeg, 1e-11) << degrees;
        }
      }
    }
  }
}

// crank-rocker-3d.yaml moves as the planar crank-rocker.yaml: the rocker angle and the coupler
// point at every crank angle (both models closed by the same Gauss–Newton, one planar and one
// spatial).
TEST(SpatialFile, CrankRocker3dMovesAsThePlanarFile) {
  const Model s3 = load_mechanism(test::source_path("mechanisms/crank-rocker-3d.yaml"));
  const Model s2 = load_mechanism(test::source_path("mechanisms/crank-rocker.yaml"));
  VecX q3 = s3.design_q(), q2 = s2.design_q();
  PositionOptions h3, h2;
  h3.locked_joint = s3.find_joint("A0");
  h2.locked_joint = s2.find_joint("A0");
  for (int degrees = 65; degrees <= 175; degrees += 5) {
    h3.locked_value = h2.locked_value = degrees * kDeg;
    ASSERT_EQ(project_positions(s3, q3, h3).status, SolveStatus::converged) << degrees;
    ASSERT_EQ(project_positions(s2, q2, h2).status, SolveStatus::converged) << degrees;
    EXPECT_NEAR(measure(s3, "rocker_angle", q3), measure(s2, "rocker_angle", q2), 1e-11) << degrees;
    EXPECT_NEAR(measure(s3, "P_x", q3), measure(s2, "P_x", q2), 1e-13) << degrees;
    EXPECT_NEAR(measure(s3, "P_y", q3), measure(s2, "P_y", q2), 1e-13) << degrees;
  }
}

// End to end: `simulate` from heavy-top.yaml's own `initial` rates is the steady precession —
// the nutation stays 30° and the centre of mass turns about z at Ω_slow (M3).
TEST(SpatialFile, HeavyTopFileSimulatesTheSteadyPrecession) {
  const auto r = test::run_cli({"simulate", test::source_path("mechanisms/heavy-top.yaml"),
                                "--t-end", "1", "--rtol", "1e-10", "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto& t = j["samples"]["t"];
  const auto& m = j["samples"]["measures"];
  ASSERT_GT(t.size(), 10u);
  const double C = 0.004, AO = 0.012, w3 = 100, th = 30 * kDeg, mgl = 9.81 * 0.1;
  const double Om =
      (C * w3 - std::sqrt(C * C * w3 * w3 - 4 * AO * mgl * std::cos(th))) / (2 * AO * std::cos(th));
  for (size_t k = 0; k < t.size(); ++k) {
    const double time = t[k].get<double>();
    EXPECT_NEAR(m["nutation"][k].get<double>(), 30.0, 1e-7) << time;  // deg
    const double angle = std::atan2(m["com_y"][k].get<double>(), m["com_x"][k].get<double>());
    EXPECT_NEAR(std::remainder(angle - Om * time, 2 * std::numbers::pi), 0.0, 1e-9) << time;
  }
}

// ---- the forms of the format, against explicit formulas ----------------------------------------
const char* kForms = R"(orthomech: 1
dimension: 3
units: {length: m, angle: deg}
ground:
  points: {O: [0, 0, 0]}
bodies:
  - name: aa
    mass: 1
    inertia: [0.3, 0.25, 0.12, 0.02, -0.01, 0.03]
    com: [0.1, 0.2, 0.3]
    pose: {position: [1, 2, 3], orientation: {axis: [1, 2, 2], angle: 50}}
    points: {P: [0.5, 0, 0]}
  - name: eu
    mass: 1
    inertia: {xx: 0.3, yy: 0.25, zz: 0.12, xy: 0.02, xz: -0.01, yz: 0.03}
    pose: {position: [0, 0, 0], orientation: {euler: [30, -20, 70], sequence: zyx}}
  - name: qu
    mass: 1
    inertia: [1, 1, 1]
    pose: {position: [0, 0, 0], orientation: {quaternion: [2, 1, 0, -1]}}
  - name: yz
    mass: 1
    inertia: [1, 1, 1]
    pose: {position: [0, 0, 0], orientation: {y: [0, 2, 0], z: [1, 0, 1]}}
  - name: ze
    mass: 1
    inertia: [1, 1, 1]
    pose: {position: [0, 0, 0], orientation: {euler: [40, 60, -10], sequence: zxz}}
joints:
  - {name: R, type: revolute, connects: [ground.O, aa.P], axis: [0, 1, 1]}
  - {name: S, type: screw, connects: [aa.P, eu.origin], axis: [1, 0, 0], ref: [1, 1, 0], pitch: 0.01}
)";

TEST(SpatialFile, OrientationFormsAndInertiaMatchExplicitFormulas) {
  const Model m = parse_mechanism(kForms, "forms.yaml");
  ASSERT_EQ(m.dimension, 3);
  // Axis–angle: Rodrigues R = I + sin a K + (1 − cos a) K².
  const Vec3 n = Vec3(1, 2, 2) / 3.0;
  const Mat3 K = skew(n);
  const double a = 50 * kDeg;
  EXPECT_LT(
      (design_R(m, "aa") - (Mat3::Identity() + std::sin(a) * K + (1 - std::cos(a)) * K * K)).norm(),
      1e-14);
  // Intrinsic z-y-x: R = Rz(a1) Ry(a2) Rx(a3); z-x-z: Rz Rx Rz.
  EXPECT_LT((design_R(m, "eu") - rz(30 * kDeg) * ry(-20 * kDeg) * rx(70 * kDeg)).norm(), 1e-14);
  EXPECT_LT((design_R(m, "ze") - rz(40 * kDeg) * rx(60 * kDeg) * rz(-10 * kDeg)).norm(), 1e-14);
  // Quaternion (2, 1, 0, −1)/√6: the usual (e0² − εᵀε) I + 2εεᵀ + 2e0 ε̃.
  const double e0 = 2 / std::sqrt(6.0);
  const Vec3 eps = Vec3(1, 0, -1) / std::sqrt(6.0);
  EXPECT_LT((design_R(m, "qu") - ((e0 * e0 - eps.dot(eps)) * Mat3::Identity() +
                                  2 * eps * eps.transpose() + 2 * e0 * skew(eps)))
                .norm(),
            1e-14);
  // Two axes, y first (kept), z made perpendicular, x = y × z.
  Mat3 Ryz;
  Ryz.col(1) = Vec3::UnitY();
  Ryz.col(2) = Vec3(1, 0, 1).normalized();
  Ryz.col(0) = Ryz.col(1).cross(Ryz.col(2));
  EXPECT_LT((design_R(m, "yz") - Ryz).norm(), 1e-14);
  // Six inertia values: the tensor J with J_xy = 0.02 etc. (tensor components).
  Mat3 J;
  J << 0.3, 0.02, -0.01, 0.02, 0.25, 0.03, -0.01, 0.03, 0.12;
  EXPECT_EQ(m.bodies[0].spatial.inertia, J);
  EXPECT_EQ(m.bodies[1].spatial.inertia, J);  // the same by name
  // The centre of mass of aa in world: position + R com.
  const VecX q = m.design_q();
  EXPECT_LT((q.segment<3>(0) - (Vec3(1, 2, 3) + design_R(m, "aa") * Vec3(0.1, 0.2, 0.3))).norm(),
            1e-14);
  // The screw's ref [1, 1, 0] is projected perpendicular to the axis [1, 0, 0]: f = y in aa's
  // frame; the pitch is stored per turn.
  const SpatialJoint& S = spatial_joint(m, "S");
  EXPECT_LT((S.frame_i.col(0) - Vec3::UnitY()).norm(), 1e-14);
  EXPECT_LT((S.frame_i.col(2) - Vec3::UnitX()).norm(), 1e-14);
  EXPECT_EQ(S.pitch, 0.01);
  // The revolute's default ref: the ground axis least aligned with (0, 1, 1)/√2 is x.
  const SpatialJoint& R = spatial_joint(m, "R");
  EXPECT_LT((R.frame_i.col(0) - Vec3::UnitX()).norm(), 1e-14);
  EXPECT_LT((R.frame_i.col(2) - Vec3(0, 1, 1).normalized()).norm(), 1e-14);
  // The revolute's points do not coincide (aa.P is not at the origin): a warning, with its place.
  ASSERT_EQ(m.warnings.size(), 2u);  // R: points apart; S: eu.origin off the screw axis
  EXPECT_NE(m.warnings[0].find("forms.yaml:30:"), std::string::npos) << m.warnings[0];
  EXPECT_NE(m.warnings[0].find("joint 'R': its points are"), std::string::npos) << m.warnings[0];
}

// Parameters, units and `--set` work in dimension 3 as in the planar format.
TEST(SpatialFile, ParametersAndSetApply) {
  const std::string text = R"(orthomech: 1
dimension: 3
parameters: {L: 200}
units: {length: mm, angle: deg}
ground:
  points: {O: [0, 0, 0]}
bodies:
  - name: rod
    mass: 1
    inertia: [10, 1000, 1000]
    com: [L/2, 0, 0]
    pose: {position: [0, 0, 0]}
    points: {O: [0, 0, 0], E: [L, 0, 0]}
joints:
  - {name: S, type: spherical, connects: [ground.O, rod.O]}
)";
  const Model m = parse_mechanism(text, "p.yaml", {{"L", "300"}});
  EXPECT_NEAR(m.bodies[0].spatial.com_local.x(), 0.15, 1e-15);
  EXPECT_NEAR(m.bodies[0].spatial.inertia(1, 1), 1e-3, 1e-18);
  EXPECT_EQ(m.nc, 3);
}

// A planar file reads as before: `dimension: 2` is the default and changes nothing.
TEST(SpatialFile, DimensionTwoIsThePlanarFormat) {
  const std::string path = test::source_path("mechanisms/crank-rocker.yaml");
  const Model a = load_mechanism(path);
  const Model b = load_mechanism(path, {{"dimension", "2"}});
  EXPECT_EQ(a.dimension, 2);
  EXPECT_EQ(b.dimension, 2);
  EXPECT_EQ(a.design_q(), b.design_q());
  EXPECT_EQ(a.nc, b.nc);
}

}  // namespace
}  // namespace orthomech

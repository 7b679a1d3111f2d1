// The rolling disc under `simulate` (docs/spatial.md §3.1): steady circular rolling (D1) reproduced
// from its closed form for two cases (tilt constant, the centre on its circle, heading Ω t,
// w·a = s_r, energy constant) in both dynamics forms; the contact force equals the closed form
// F = m Ω V e2 + m g k (normal force m g, friction m Ω V toward the circle's centre); the file
// mechanisms/rolling-disc.yaml reads to the same model and its `initial` rates give the same
// motion; the dual and primal forms agree on it (crosscheck); the reader's keys; the CLI.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/rolling_disc.hpp"
#include "orthomech/dynamics/crosscheck.hpp"
#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

constexpr double kRho = 0.1, kMass = 1.0, kA = 0.0025, kCs = 0.005, kG = 9.81;

// Steady circular rolling (D1) at tilt θ and precession Ω, contact at the origin, heading x.
struct Steady {
  double theta, Omega;
  [[nodiscard]] double spin() const {  // s_r from (D1)
    const double s = std::sin(theta), c = std::cos(theta);
    return (kA * Omega * Omega * s * c - kMass * kG * kRho * s) /
           ((kCs + kMass * kRho * kRho) * Omega * c);
  }
  [[nodiscard]] double speed() const { return kRho * spin(); }     // V
  [[nodiscard]] double radius() const { return speed() / Omega; }  // R_c
  [[nodiscard]] Vec3 axis() const { return {0.0, std::cos(theta), std::sin(theta)}; }
  [[nodiscard]] Vec3 centre0() const { return kRho * Vec3(0.0, -std::sin(theta), std::cos(theta)); }
  [[nodiscard]] Mat3 frame() const {  // R0 = [e1, a × e1, a]
    Mat3 R;
    R << Vec3::UnitX(), axis().cross(Vec3::UnitX()), axis();
    return R;
  }
};

Quat quaternion_of(const Mat3& R) {
  const Eigen::Quaterniond q(R);
  return Quat(q.w(), q.x(), q.y(), q.z());
}

// The disc as a model built in code, at the initial pose of `st`.
Model disc_model(const Steady& st) {
  Model m;
  m.name = "disc";
  m.dimension = 3;
  Body b;
  b.name = "disc";
  b.kind = BodyKind::spatial;
  b.mass = kMass;
  b.spatial.inertia = Vec3(kA, kA, kCs).asDiagonal();
  b.spatial.design_position = st.centre0();
  b.spatial.design_orientation = quaternion_of(st.frame());
  m.bodies.push_back(b);
  RollingDisc d;
  d.name = "contact";
  d.body = 0;
  d.radius = kRho;
  m.rolling_discs.push_back(d);
  Load g;
  g.name = "weight";
  g.kind = SpatialGravity{Vec3(0, 0, -kG)};
  m.loads.push_back(g);
  finalize_model(m);
  return m;
}

State initial_state(const Model& m, const Steady& st) {
  State s(m);
  s.q = m.design_q();
  const double sigma = st.spin() - st.Omega * std::sin(st.theta);
  const Vec3 w = st.Omega * Vec3::UnitZ() + sigma * st.axis();
  s.u.head<3>() = Vec3(st.speed(), 0.0, 0.0);
  s.u.tail<3>() = st.frame().transpose() * w;
  return s;
}

SimulateOptions options(DynamicsForm form) {
  SimulateOptions o;
  o.form = form;
  o.t_end = 2.0;
  o.dt_out = 0.02;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.use_file_rates = false;
  return o;
}

// Deviations from the steady motion over a run; `reactions` at index `first` onward are the disc's
// Fx, Fy, Fz, Ft1, Ft2, N.
struct Deviation {
  double tilt = 0, circle = 0, heading = 0, spin = 0, force = 0, normal = 0;
};
Deviation deviation(const SimulateResult& r, const Steady& st, size_t first) {
  Deviation d;
  const Vec3 c0 = st.centre0();
  const Vec2 centre = Vec2(c0.x(), c0.y()) + st.radius() * Vec2::UnitY();  // r_C,xy + R_c e2
  for (const SimulationSample& smp : r.samples) {
    const Mat3 R = rotation_matrix(smp.q.segment<4>(3));
    const Vec3 a = R.col(2), w = R * smp.u.tail<3>();
    d.tilt = std::max(d.tilt, std::abs(std::asin(a.z()) - st.theta));
    const Vec2 rc(smp.q(0), smp.q(1));
    d.circle = std::max(d.circle, std::abs((rc - centre).norm() - std::abs(st.radius())));
    // Heading: the horizontal projection of the axis, e2(t) = Rz(Ω t) e2.
    const double psi = std::atan2(-a.x(), a.y());
    d.heading =
        std::max(d.heading, std::abs(std::remainder(psi - st.Omega * smp.t, 2 * std::numbers::pi)));
    d.spin = std::max(d.spin, std::abs(w.dot(a) - st.spin()));
    // Contact force: F = m Ω V e2(t) + m g k.
    const Vec3 e2 = Vec3(-std::sin(st.Omega * smp.t), std::cos(st.Omega * smp.t), 0.0);
    const Vec3 F_expected = kMass * st.Omega * st.speed() * e2 + kMass * kG * Vec3::UnitZ();
    const Vec3 F(smp.reactions[first], smp.reactions[first + 1], smp.reactions[first + 2]);
    d.force = std::max(d.force, (F - F_expected).norm());
    d.normal = std::max(d.normal, std::abs(smp.reactions[first + 5] - kMass * kG));
  }
  return d;
}

TEST(RollingDiscDynamics, ClosedFormOfTheSteadyMotion) {  // docs/spatial.md §3.1's numbers
  const Steady a{20 * std::numbers::pi / 180, 3.0}, b{-35 * std::numbers::pi / 180, 5.0};
  EXPECT_NEAR(a.spin(), -7.763541035340376, 1e-13);
  EXPECT_NEAR(a.speed(), -0.7763541035340377, 1e-14);
  EXPECT_NEAR(a.radius(), -0.25878470117801256, 1e-14);
  EXPECT_NEAR(b.spin(), 8.68073423615713, 1e-13);
  EXPECT_NEAR(b.radius(), 0.17361468472314262, 1e-14);
  // ω_body of case a (docs/spatial.md: (0, −2.81907786, −7.76354104) rad/s).
  const Model m = disc_model(a);
  const State s = initial_state(m, a);
  EXPECT_NEAR(s.u(3), 0.0, 1e-14);
  EXPECT_NEAR(s.u(4), -2.81907786, 1e-8);
  EXPECT_NEAR(s.u(5), -7.76354104, 1e-8);
}

TEST(RollingDiscDynamics, SteadyCircularRollingInBothForms) {
  for (const Steady st :
       {Steady{20 * std::numbers::pi / 180, 3.0}, Steady{-35 * std::numbers::pi / 180, 5.0}}) {
    const Model m = disc_model(st);
    const State s = initial_state(m, st);
    // Admissible: the contact point's material velocity vanishes.
    MatX Et(m.nc, m.n);
    compute_constraint_jacobian(m, s.q, Et);
    ASSERT_LT((Et * s.u).cwiseAbs().maxCoeff(), 1e-14);
    for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
      const SimulateResult r = simulate(m, s, options(form));
      ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
      EXPECT_NEAR(r.kinetic_removed, 0.0, 1e-12);
      ASSERT_EQ(r.components.size(), 6u);
      EXPECT_EQ(r.components[0].name, "contact.Fx");
      EXPECT_EQ(r.components[5].name, "contact.N");
      const Deviation d = deviation(r, st, 0);
      const std::string what =
          "θ = " + std::to_string(st.theta) + ", form " + std::to_string(static_cast<int>(form));
      EXPECT_LT(d.tilt, 1e-8) << what;
      EXPECT_LT(d.circle, 1e-8) << what;
      EXPECT_LT(d.heading, 1e-8) << what;
      EXPECT_LT(d.spin, 1e-8) << what;
      EXPECT_LT(d.force, 1e-7) << what;  // N, against m g = 9.81 N
      EXPECT_LT(d.normal, 1e-7) << what;
      EXPECT_LT(r.energy_max_drift, 1e-9) << what;
      EXPECT_GT(r.samples.back().t, 1.99);
    }
  }
}

std::string source(const std::string& rel) { return std::string(ORTHOMECH_SOURCE_DIR) + "/" + rel; }

// The bundled file: the same model (mobility, design pose), and its `initial` rates give the
// steady motion of case θ = 20°, Ω = 3.
TEST(RollingDiscDynamics, BundledFileRollsSteadily) {
  const Model m = load_mechanism(source("mechanisms/rolling-disc.yaml"));
  EXPECT_TRUE(m.warnings.empty());
  ASSERT_EQ(m.rolling_discs.size(), 1u);
  EXPECT_EQ(m.n, 6);
  EXPECT_EQ(m.nc, 3);
  const VecX q = m.design_q();
  EXPECT_EQ(compute_mobility(m, q).rank, 3);
  const Steady st{20 * std::numbers::pi / 180, 3.0};
  const Model code = disc_model(st);
  EXPECT_LT((q - code.design_q()).cwiseAbs().maxCoeff(), 1e-15);
  VecX f(m.nc);
  compute_constraint_residual(m, q, f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-16);
  SimulateOptions o = options(DynamicsForm::dual);
  o.use_file_rates = true;
  const SimulateResult r = simulate(m, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  const State s = initial_state(code, st);
  EXPECT_LT((r.samples.front().u - s.u).cwiseAbs().maxCoeff(), 1e-12);
  const Deviation d = deviation(r, st, 0);
  EXPECT_LT(d.tilt, 1e-8);
  EXPECT_LT(d.circle, 1e-8);
  EXPECT_LT(d.heading, 1e-8);
  EXPECT_LT(d.spin, 1e-8);
  EXPECT_LT(d.force, 1e-7);
}

// Dual and primal forms and the paper's identities agree on the bundled disc.
TEST(RollingDiscDynamics, CrosscheckPassesOnTheBundledFile) {
  const Model m = load_mechanism(source("mechanisms/rolling-disc.yaml"));
  const CrosscheckResult r = run_crosscheck(m);
  EXPECT_TRUE(r.pass) << r.message;
  EXPECT_TRUE(r.primal_checked);
  for (const CrosscheckItem& it : r.items)
    EXPECT_TRUE(it.pass) << it.name << " " << it.max_relative;
}

// A disc that does not touch the plane at the design pose is a warning; the position solvers
// put it on the plane.
TEST(RollingDiscDynamics, GapAtTheDesignPoseIsAWarningAndIsClosed) {
  std::ifstream in(source("mechanisms/rolling-disc.yaml"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string from = "position: [0, -0.03420201433256687, 0.09396926207859085]";
  ASSERT_NE(text.find(from), std::string::npos);
  text.replace(text.find(from), from.size(),
               "position: [0, -0.03420201433256687, 0.10396926207859085]");
  const Model m = parse_mechanism(text, "disc.yaml");
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_NE(m.warnings[0].find("rolling disc 'contact': its lowest rim point is 0.01 m above the "
                               "plane at the design pose"),
            std::string::npos)
      << m.warnings[0];
  SimulateOptions o = options(DynamicsForm::dual);
  o.t_end = 0.1;
  const SimulateResult r = simulate(m, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  for (const SimulationSample& smp : r.samples) EXPECT_LT(smp.residual, 1e-9);
}

// The reader: `centre` (a point of the disc's body, from the centre of mass), `plane` (point,
// normal normalised) and `t1` (made perpendicular to the normal; default the world axis least
// aligned with the normal, projected), in the file's units.
TEST(RollingDiscDynamics, ReaderTakesCentrePlaneAndT1) {
  const auto read = [](const std::string& disc) {
    return parse_mechanism(
        "orthomech: 1\ndimension: 3\nunits: {length: mm, angle: deg, mass: kg}\n"
        "bodies:\n  - name: wheel\n    mass: 1\n    inertia: [2500, 2500, 5000]\n"
        "    com: [0, 0, 10]\n    pose: {position: [0, 0, 100], orientation: {x: [1, 0, 0], "
        "z: [0, 1, 0]}}\n    points: {H: [0, 0, 30]}\n"
        "nonholonomic:\n  - {name: c, type: rolling-disc, body: wheel, radius: 100, axis: [0, 0, "
        "2]" +
            disc + "}\n",
        "wheel.yaml");
  };
  {
    const Model m = read(", centre: wheel.H, plane: {point: [0, 0, -5], normal: [0, 0, 3]}");
    ASSERT_EQ(m.rolling_discs.size(), 1u);
    const RollingDisc& d = m.rolling_discs[0];
    EXPECT_EQ(d.body, 0);
    EXPECT_DOUBLE_EQ(d.radius, 0.1);
    EXPECT_LT((d.axis_local - Vec3::UnitZ()).norm(), 1e-15);
    EXPECT_LT((d.centre_local - Vec3(0, 0, 0.02)).norm(), 1e-15);  // H − com
    EXPECT_LT((d.plane_point - Vec3(0, 0, -0.005)).norm(), 1e-15);
    EXPECT_LT((d.normal - Vec3::UnitZ()).norm(), 1e-15);
    EXPECT_LT((d.t1 - Vec3::UnitX()).norm(), 1e-15);
    EXPECT_EQ(d.row_offset, 0);
    // The disc centre H is 0.1 m up, the axis horizontal: the lowest rim point is at z = 0,
    // 5 mm above the plane z = −5 mm: a warning.
    ASSERT_EQ(m.warnings.size(), 1u);
    EXPECT_NE(m.warnings[0].find("its lowest rim point is 5 mm above"), std::string::npos)
        << m.warnings[0];
  }
  {
    const Model m = read(", t1: [1, 1, 0.5]");
    EXPECT_LT((m.rolling_discs[0].t1 - Vec3(1, 1, 0).normalized()).norm(), 1e-15);
  }
  {
    const Model m = read(", plane: {normal: [1, 1, 0]}");
    EXPECT_LT((m.rolling_discs[0].t1 - Vec3::UnitZ()).norm(), 1e-15);  // z least aligned
    EXPECT_LT((m.rolling_discs[0].normal - Vec3(1, 1, 0).normalized()).norm(), 1e-15);
  }
}

// The command line: `simulate` completes on the bundled file and reports the contact force
// (normal force m g, friction m Ω V toward the centre of the circle: at t = 0 along −y).
TEST(RollingDiscDynamics, SimulateCliReportsTheContactForce) {
  const test::CliResult r = test::run_cli({"simulate", test::bundled_file("rolling-disc"),
                                           "--t-end", "1", "--rtol", "1e-10", "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "completed");
  const auto& reactions = j["samples"]["reactions"];
  for (const char* c :
       {"contact.Fx", "contact.Fy", "contact.Fz", "contact.Ft1", "contact.Ft2", "contact.N"})
    ASSERT_TRUE(reactions.contains(c)) << c;
  const double friction = kMass * 3.0 * Steady{20 * std::numbers::pi / 180, 3.0}.speed();
  EXPECT_NEAR(reactions["contact.N"][0].get<double>(), kMass * kG, 1e-7);
  EXPECT_NEAR(reactions["contact.Fz"].back().get<double>(), kMass * kG, 1e-7);
  EXPECT_NEAR(reactions["contact.Fy"][0].get<double>(), friction, 1e-7);  // e2 = y at t = 0
  EXPECT_NEAR(reactions["contact.Fx"][0].get<double>(), 0.0, 1e-7);
  const test::CliResult text =
      test::run_cli({"crosscheck", test::bundled_file("rolling-disc"), "--json"});
  EXPECT_EQ(text.status, 0) << text.err;
  EXPECT_TRUE(nlohmann::json::parse(text.out)["pass"].get<bool>());
}

}  // namespace
}  // namespace orthomech

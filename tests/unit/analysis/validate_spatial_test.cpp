// validate on spatial mechanisms (issue 13 item 2) against independent oracles:
//  - RSSR positions against the closed form (M1) of docs/spatial.md §4.1 (rocker angle φ(θ)), its
//    dead points of the rocker input from dφ/dθ = 0 of (M1), solved in the test by bisection;
//  - Bennett positions against the closure tan(θ1/2) tan(θ2/2) = sin((β+α)/2)/sin((β−α)/2) and its
//    DOF 1 with 3 redundant equations at every position (docs/spatial.md §4.2);
//  - σ_min and η against an SVD of the Jacobian built in the test by central differences of f and
//    of the input through q ⊕ h·e_k (integrate_positions), with the mass matrix assembled in the
//    test from the bodies' masses and inertia tensors;
//  - the idle spin of an S–S coupler (docs/spatial.md §4.1): held by the row e_ωx of the coupler
//    (its long axis), written in the test.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "orthomech/analysis/validate.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

double wrap(double a) { return a - 2.0 * kPi * std::round(a / (2.0 * kPi)); }

// ---- (M1): the RSSR of mechanisms/rssr.yaml, SI ------------------------------------------------
constexpr double r1 = 0.1, r2 = 0.2, p = 0.3, h = 0.2, Lc = 0.42;
struct M1 {
  double P, Q, S, dP, dS;
  explicit M1(double theta)
      : P(-2.0 * r1 * r2 * std::sin(theta)),
        Q(2.0 * h * r2),
        S(p * p + r1 * r1 + r2 * r2 + h * h - Lc * Lc - 2.0 * p * r1 * std::cos(theta)),
        dP(-2.0 * r1 * r2 * std::cos(theta)),
        dS(2.0 * p * r1 * std::sin(theta)) {}
};
double rocker(double theta) {  // the file's branch
  const M1 m(theta);
  return std::atan2(m.Q, m.P) + std::acos(-m.S / std::hypot(m.P, m.Q));
}
double rocker_slope(double theta) {  // dφ/dθ
  const M1 m(theta);
  const double phi = rocker(theta);
  return -(m.dP * std::cos(phi) + m.dS) / (-m.P * std::sin(phi) + m.Q * std::cos(phi));
}

// The transmission index is checked in its own tests below: elsewhere any index passes (the
// RSSR's is 0.29 … 0.53 over the turn, below the default bound 0.5 at most crank angles).
ValidateOptions any_index() {
  ValidateOptions o;
  o.min_transmission_index = 0.0;
  return o;
}

DesignPosition position(const std::string& name, int joint, double value) {
  DesignPosition d;
  d.name = name;
  d.inputs = {{joint, value}};
  return d;
}

// The mass matrix from the bodies' data (docs/spatial.md §1.4: M_b = diag(m I₃, J)).
MatX mass_matrix(const Model& m) {
  MatX M = MatX::Zero(m.n, m.n);
  for (const Body& b : m.bodies) {
    M.block(b.u_offset, b.u_offset, 3, 3) = b.mass * Mat3::Identity();
    M.block(b.u_offset + 3, b.u_offset + 3, 3, 3) = b.spatial.inertia;
  }
  return M;
}

// Columns k of ∂f/∂u and ∂s/∂u by central differences along q ⊕ ±ε e_k.
struct DifferenceJacobian {
  MatX Et;
  MatX d;  // one row per input
};
DifferenceJacobian difference_jacobian(const Model& m, const VecX& q, const std::vector<int>& in) {
  constexpr double eps = 1e-6;
  DifferenceJacobian J{MatX(m.nc, m.n), MatX(static_cast<Eigen::Index>(in.size()), m.n)};
  VecX fp(m.nc), fm(m.nc);
  for (int k = 0; k < m.n; ++k) {
    VecX e = VecX::Zero(m.n);
    e(k) = 1.0;
    VecX qp = q, qm = q;
    integrate_positions(m, qp, e, eps);
    integrate_positions(m, qm, e, -eps);
    compute_constraint_residual(m, qp, fp);
    compute_constraint_residual(m, qm, fm);
    J.Et.col(k) = (fp - fm) / (2.0 * eps);
    for (size_t i = 0; i < in.size(); ++i)
      J.d(static_cast<Eigen::Index>(i), k) =
          wrap(joint_coordinate(m, in[i], qp) - joint_coordinate(m, in[i], qm)) / (2.0 * eps);
  }
  return J;
}

// σ_r/σ_1 of the rows, columns scaled by √A_kk (A = M⁻¹), rows normalised.
VecX scaled_singular_values(const Model& m, MatX J) {
  const MatX A = mass_matrix(m).inverse();
  for (int k = 0; k < m.n; ++k) J.col(k) *= std::sqrt(A(k, k));
  for (Eigen::Index r = 0; r < J.rows(); ++r) J.row(r).normalize();
  return Eigen::JacobiSVD<MatX>(J).singularValues();
}

void expect_unit_quaternions(const Model& m, const VecX& q) {
  for (const Body& b : m.bodies)
    EXPECT_NEAR(q.segment<4>(b.q_offset + 3).norm(), 1.0, 1e-12) << b.name;
}

// ---- RSSR --------------------------------------------------------------------------------------

// Positions of the crank input at 0°, 90°, 180°, 270°: the rocker angle is (M1)'s φ(θ); DOF 1,
// no redundancy; the crank turns fully (no dead point of the crank input, one circuit); σ_min
// and η equal the difference-Jacobian oracle.
TEST(SpatialValidate, RssrCrankPositionsMatchClosedFormM1) {
  Model m = test::load_bundled("rssr");
  const int A0 = m.find_joint("A0"), B0 = m.find_joint("B0");
  m.design_positions.clear();
  for (int k = 0; k < 4; ++k)
    m.design_positions.push_back(position(std::to_string(90 * k) + "deg", A0, 90.0 * k * kDeg));
  const ValidationReport rep = validate_design_positions(m, any_index());
  ASSERT_EQ(rep.positions.size(), 4u);
  EXPECT_EQ(rep.input, "A0");
  EXPECT_TRUE(rep.input_angular);
  EXPECT_EQ(rep.generic_rank, 17);
  EXPECT_EQ(rep.circuits, 1);
  EXPECT_TRUE(rep.singular_points.empty());
  EXPECT_FALSE(rep.circuit_defect || rep.branch_defect || rep.order_defect);
  EXPECT_EQ(rep.not_applicable.size(), 3u);
  for (int k = 0; k < 4; ++k) {
    const PositionReport& pr = rep.positions[static_cast<size_t>(k)];
    ASSERT_TRUE(pr.assembles) << pr.name << ": " << pr.assembly_message;
    EXPECT_TRUE(pr.pass()) << pr.name << ": " << (pr.failures.empty() ? "" : pr.failures[0]);
    const double theta = 90.0 * k * kDeg;
    EXPECT_NEAR(wrap(joint_coordinate(m, A0, pr.q) - theta), 0.0, 1e-11) << pr.name;
    EXPECT_NEAR(wrap(joint_coordinate(m, B0, pr.q) - rocker(theta)), 0.0, 1e-9) << pr.name;
    EXPECT_EQ(pr.dof, 1);
    EXPECT_EQ(pr.rank, 17);
    EXPECT_TRUE(pr.redundant.empty());
    EXPECT_TRUE(pr.idle.empty());
    EXPECT_TRUE(pr.four_bars.empty());
    EXPECT_EQ(pr.circuit, 1);
    EXPECT_EQ(pr.branch, 1);
    EXPECT_FALSE(pr.singular_distance.has_value());  // no dead point of the crank
    expect_unit_quaternions(m, pr.q);
    // σ_min (rank 17 of 17 rows) and η of [Eᵀ; d] from differences.
    const DifferenceJacobian J = difference_jacobian(m, pr.q, {A0});
    const VecX s = scaled_singular_values(m, J.Et);
    EXPECT_NEAR(pr.singular.sigma_min, s(16) / s(0), 1e-7 * s(16) / s(0)) << pr.name;
    MatX Jd(m.nc + 1, m.n);
    Jd << J.Et, J.d;
    const VecX sd = scaled_singular_values(m, Jd);
    ASSERT_TRUE(pr.singular.eta.has_value());
    EXPECT_NEAR(*pr.singular.eta, sd(m.n - 1) / sd(0), 1e-7 * sd(m.n - 1) / sd(0)) << pr.name;
  }
  // The inputs increase by 90° per position and span less than a turn: no order defect; but in
  // reverse order with a repeated step back they do not.
  std::swap(m.design_positions[1], m.design_positions[2]);
  EXPECT_TRUE(validate_design_positions(m).order_defect);
}

// With the rocker as the input, its dead points are the extremes of φ(θ) on the circuit: dφ/dθ = 0
// of (M1), found here by bisection on a 1° grid. The distance to the nearest one and its value.
TEST(SpatialValidate, RssrRockerInputDeadPointsAreExtremesOfM1) {
  Model m = test::load_bundled("rssr");
  const int B0 = m.find_joint("B0");
  // The extremes of φ over a full turn of the crank.
  std::vector<double> extremes;
  for (int k = 0; k < 360; ++k) {
    double a = k * kDeg, b = (k + 1) * kDeg;
    if (rocker_slope(a) * rocker_slope(b) > 0.0) continue;
    for (int it = 0; it < 200 && b - a > 1e-15; ++it) {
      const double c = 0.5 * (a + b);
      (rocker_slope(a) * rocker_slope(c) <= 0.0 ? b : a) = c;
    }
    extremes.push_back(rocker(0.5 * (a + b)));
  }
  ASSERT_EQ(extremes.size(), 2u);  // the rocker's two limit positions
  const double phi_a = rocker(30.0 * kDeg), phi_b = rocker(60.0 * kDeg);
  m.design_positions = {position("a", B0, phi_a), position("b", B0, phi_b)};
  const ValidationReport rep = validate_design_positions(m);
  ASSERT_EQ(rep.positions.size(), 2u);
  EXPECT_EQ(rep.circuits, 1);
  ASSERT_EQ(rep.singular_points.size(), 2u);
  for (const std::string& s : rep.singular_points)
    EXPECT_NE(s.find("dead point of input 'B0'"), std::string::npos) << s;
  for (const PositionReport& pr : rep.positions) {
    ASSERT_TRUE(pr.assembles) << pr.assembly_message;
    const double phi = joint_coordinate(m, B0, pr.q);
    size_t nearest = 0;
    for (size_t k = 1; k < extremes.size(); ++k)
      if (std::abs(wrap(extremes[k] - phi)) < std::abs(wrap(extremes[nearest] - phi))) nearest = k;
    ASSERT_TRUE(pr.singular_distance.has_value()) << pr.name;
    EXPECT_EQ(pr.singular_kind, "dead point");
    EXPECT_NEAR(*pr.singular_distance, std::abs(wrap(extremes[nearest] - phi)), 1e-8) << pr.name;
    EXPECT_NEAR(wrap(*pr.singular_input - extremes[nearest]), 0.0, 1e-8) << pr.name;
    EXPECT_EQ(pr.circuit, 1);
  }
  // Both positions lie on the rising side of φ(θ) (dφ/dθ > 0 at 30° and 60°): one branch.
  EXPECT_EQ(rep.positions[0].branch, rep.positions[1].branch);
  EXPECT_FALSE(rep.branch_defect);
  // The crank angle there: on the design's mode (θ = 30°, 60°).
  EXPECT_NEAR(wrap(joint_coordinate(m, m.find_joint("A0"), rep.positions[1].q) - 60.0 * kDeg), 0.0,
              1e-9);
}

// The assembly modes at the crank input 30°: the rocker's two roots of (M1)
// (φ = atan2(Q, P) ± acos(−S/√(P² + Q²)), both real: |S| < √(P² + Q²)) times the coupler turned a
// half-turn about AB (the universal joint's pin rows hold both ways) = 4; the position itself is
// on the file's root (+).
TEST(SpatialValidate, RssrHasFourAssemblyModesAtACrankAngle) {
  Model m = test::load_bundled("rssr");
  const int A0 = m.find_joint("A0"), B0 = m.find_joint("B0");
  const double theta = 30.0 * kDeg;
  const M1 c(theta);
  const double root[2] = {std::atan2(c.Q, c.P) + std::acos(-c.S / std::hypot(c.P, c.Q)),
                          std::atan2(c.Q, c.P) - std::acos(-c.S / std::hypot(c.P, c.Q))};
  m.design_positions = {position("p30", A0, theta)};
  ValidateOptions o;
  o.starts = 64;
  const ValidationReport rep = validate_design_positions(m, o);
  ASSERT_EQ(rep.positions.size(), 1u);
  const PositionReport& pr = rep.positions[0];
  EXPECT_EQ(pr.modes, 4);
  EXPECT_NEAR(wrap(joint_coordinate(m, B0, pr.q) - root[0]), 0.0, 1e-9);
  // The two roots are distinct (the oracle's modes are not one).
  EXPECT_GT(std::abs(wrap(root[1] - root[0])), 0.1);
}

// An S–S coupler (the universal joint B replaced by a spherical one) has an idle spin about AB
// (docs/spatial.md §4.1): DOF 2, one of them idle, so one input fixes the position; η is taken with
// the spin held (the row e_ωx of the coupler, its long axis, written here) and the circuit closes.
TEST(SpatialValidate, IdleSpinIsReportedAndHeld) {
  Model m = test::load_bundled("rssr");
  const int A0 = m.find_joint("A0"), B0 = m.find_joint("B0");
  std::get<SpatialJoint>(m.joints[static_cast<size_t>(m.find_joint("B"))].kind).type =
      SpatialJointType::spherical;
  finalize_model(m);
  m.design_positions = {position("p30", A0, 30.0 * kDeg), position("p120", A0, 120.0 * kDeg)};
  const ValidationReport rep = validate_design_positions(m, any_index());
  ASSERT_EQ(rep.positions.size(), 2u);
  EXPECT_EQ(rep.circuits, 1);
  for (const PositionReport& pr : rep.positions) {
    ASSERT_TRUE(pr.assembles) << pr.assembly_message;
    EXPECT_TRUE(pr.pass()) << pr.name << ": " << (pr.failures.empty() ? "" : pr.failures[0]);
    EXPECT_EQ(pr.dof, 2);
    EXPECT_EQ(pr.idle_dof, 1);
    ASSERT_EQ(pr.idle.size(), 1u);
    EXPECT_EQ(pr.idle[0].body, "coupler");
    EXPECT_EQ(pr.circuit, 1);
    const double theta = joint_coordinate(m, A0, pr.q);
    EXPECT_NEAR(wrap(joint_coordinate(m, B0, pr.q) - rocker(theta)), 0.0, 1e-9) << pr.name;
    const DifferenceJacobian J = difference_jacobian(m, pr.q, {A0});
    MatX Jd(m.nc + 2, m.n);
    VecX spin = VecX::Zero(m.n);
    spin(m.bodies[static_cast<size_t>(m.find_body("coupler"))].u_offset + 3) = 1.0;
    Jd << J.Et, J.d, spin.transpose();
    const VecX sd = scaled_singular_values(m, Jd);
    ASSERT_TRUE(pr.singular.eta.has_value());
    EXPECT_NEAR(*pr.singular.eta, sd(m.n - 1) / sd(0), 1e-7 * sd(m.n - 1) / sd(0)) << pr.name;
  }
  // Without the idle spin held the inputs would not fix the position: a second idle-free check
  // that the oracle's row matters (η of [Eᵀ; d] alone is 0).
  // [Eᵀ; d] has n_c + 1 = n − 1 rows here: padded with a zero row to n × n, its smallest
  // singular value is 0 (the oracle's singular values are n only for a square matrix).
  const DifferenceJacobian J = difference_jacobian(m, rep.positions[0].q, {A0});
  ASSERT_EQ(m.nc + 1, m.n - 1);
  MatX Jd = MatX::Zero(m.n, m.n);
  Jd.topRows(m.nc) = J.Et;
  Jd.row(m.nc) = J.d.row(0);
  const VecX sd = scaled_singular_values(m, Jd);
  ASSERT_EQ(sd.size(), m.n);
  EXPECT_LT(sd(m.n - 1) / sd(0), 1e-8);
}

// ---- the crank-rocker rebuilt with spatial bodies ----------------------------------------------

// Driven from the rocker, the dead points of mechanisms/crank-rocker-3d.yaml are the rocker's
// limit positions, crank and coupler collinear: |A0B| = b ± a, and the law of cosines in the
// triangle A0 B0 B (d = 70, c = 60 mm) gives ψ = π − acos((d² + c² − |A0B|²)/(2dc)). The planar
// file on the same inputs (a second implementation: planar bodies, 3 coordinates each) agrees.
// DOF 1 with 3 redundant equations at every position (the planar loop's out-of-plane rows).
TEST(SpatialValidate, CrankRocker3dRockerDeadPointsMatchThePlanarFile) {
  Model m = test::load_bundled("crank-rocker-3d");
  Model planar = test::load_bundled("crank-rocker");
  const int B0 = m.find_joint("B0"), pB0 = planar.find_joint("B0");
  const double d = 0.070, c = 0.060, a = 0.030, b = 0.080;
  const double psi_ext = kPi - std::acos((d * d + c * c - (a + b) * (a + b)) / (2 * d * c));
  const double psi_fold = kPi - std::acos((d * d + c * c - (b - a) * (b - a)) / (2 * d * c));
  m.design_positions = {position("r80", B0, 80.0 * kDeg), position("r120", B0, 120.0 * kDeg)};
  planar.design_positions = {position("r80", pB0, 80.0 * kDeg),
                             position("r120", pB0, 120.0 * kDeg)};
  const ValidationReport rep = validate_design_positions(m);
  const ValidationReport prep = validate_design_positions(planar);
  ASSERT_EQ(rep.positions.size(), 2u);
  EXPECT_EQ(rep.circuits, 1);
  EXPECT_EQ(rep.singular_points.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    const PositionReport& pr = rep.positions[k];
    ASSERT_TRUE(pr.assembles) << pr.assembly_message;
    EXPECT_EQ(pr.dof, 1);
    EXPECT_EQ(pr.redundant.size(), 3u);
    const double psi = joint_coordinate(m, B0, pr.q);
    const double nearest = std::abs(psi - psi_ext) < std::abs(psi - psi_fold) ? psi_ext : psi_fold;
    ASSERT_TRUE(pr.singular_distance.has_value()) << pr.name;
    EXPECT_NEAR(*pr.singular_distance, std::abs(psi - nearest), 1e-9) << pr.name;
    EXPECT_NEAR(*pr.singular_input, nearest, 1e-9) << pr.name;
    const PositionReport& pp = prep.positions[k];
    ASSERT_TRUE(pp.singular_distance.has_value());
    EXPECT_NEAR(*pr.singular_distance, *pp.singular_distance, 1e-9) << pr.name;
    EXPECT_EQ(pr.branch, pp.branch) << pr.name;
  }
}

// ---- a spatial parallelogram: change points -----------------------------------------------------

// The parallelogram of validate_test.cpp (crank 1, coupler 3 on a 3 m ground, follower 1) built
// with spatial bodies and revolutes about z: s + l = p + q, change points where all links are
// collinear, at crank 0° and 180° (closed form), where σ_min of the (redundant: rank 17 of 20
// rows) Eᵀ vanishes.
std::string spatial_parallelogram(const std::string& positions) {
  return R"(orthomech: 1
dimension: 3
units: {length: m, angle: deg}
ground:
  points: {A0: [0, 0, 0], B0: [3, 0, 0]}
bodies:
  - name: crank
    mass: 1
    inertia: [0.001, 0.1, 0.1]
    com: [0.5, 0, 0]
    pose: {position: [0, 0, 0], orientation: {axis: [0, 0, 1], angle: 30}}
    points: {A0: [0, 0, 0], A: [1, 0, 0]}
  - name: coupler
    mass: 1
    inertia: [0.001, 0.1, 0.1]
    com: [1.5, 0, 0]
    pose: {position: [0.8660254037844387, 0.5, 0]}
    points: {A: [0, 0, 0], B: [3, 0, 0]}
  - name: rocker
    mass: 1
    inertia: [0.001, 0.1, 0.1]
    com: [0.5, 0, 0]
    pose: {position: [3, 0, 0], orientation: {axis: [0, 0, 1], angle: 30}}
    points: {B0: [0, 0, 0], B: [1, 0, 0]}
joints:
  - {name: A0, type: revolute, connects: [ground.A0, crank.A0], axis: [0, 0, 1]}
  - {name: A, type: revolute, connects: [crank.A, coupler.A], axis: [0, 0, 1]}
  - {name: B, type: revolute, connects: [coupler.B, rocker.B], axis: [0, 0, 1]}
  - {name: B0, type: revolute, connects: [rocker.B0, ground.B0], axis: [0, 0, 1]}
design_positions:
)" + positions;
}

TEST(SpatialValidate, ParallelogramChangePointsDistanceAndBranchDefect) {
  constexpr double kChangePointTol = 1e-7;  // σ_min is V-shaped there: NLopt locates it closely
  {
    const ValidationReport r = validate_design_positions(parse_mechanism(
        spatial_parallelogram(
            "  - {name: p1, inputs: {A0: 30}}\n  - {name: p2, inputs: {A0: 120}}\n"),
        "spatial-para"));
    ASSERT_EQ(r.positions.size(), 2u);
    EXPECT_TRUE(r.pass()) << (r.positions[0].failures.empty() ? "" : r.positions[0].failures[0]);
    EXPECT_EQ(r.generic_rank, 17);
    for (const PositionReport& pr : r.positions) {
      EXPECT_EQ(pr.dof, 1);
      EXPECT_EQ(pr.redundant.size(), 3u);
      EXPECT_EQ(pr.singular_kind, "change point");
    }
    ASSERT_TRUE(r.positions[0].singular_distance && r.positions[1].singular_distance);
    EXPECT_NEAR(*r.positions[0].singular_distance, 30.0 * kDeg, kChangePointTol);
    EXPECT_NEAR(*r.positions[1].singular_distance, 60.0 * kDeg, kChangePointTol);
    EXPECT_NEAR(wrap(*r.positions[0].singular_input), 0.0, kChangePointTol);
    EXPECT_NEAR(wrap(*r.positions[1].singular_input - kPi), 0.0, kChangePointTol);
  }
  {
    const ValidationReport r = validate_design_positions(parse_mechanism(
        spatial_parallelogram(
            "  - {name: p1, inputs: {A0: 150}}\n  - {name: p2, inputs: {A0: 200}}\n"),
        "spatial-para"));
    EXPECT_TRUE(r.branch_defect);  // the change point at 180° lies between them
    EXPECT_FALSE(r.circuit_defect);
    EXPECT_FALSE(r.pass());
  }
}

// ---- spatial slider-crank ----------------------------------------------------------------------

// With the slide as the input, the dead points are the extremes of (M2) (docs/spatial.md §4.4):
// x_C² = 0.09 − |(0.1, 0.12) + 0.08 (cos φ, sin φ)|², extreme when the crank points along
// ±(0.1, 0.12): x_C = √(0.09 − (|(0.1, 0.12)| ± 0.08)²). A prismatic (slide) input in metres.
TEST(SpatialValidate, SliderCrankSlideInputDeadPointsFromM2) {
  Model m = test::load_bundled("spatial-slider-crank");
  const int slide = m.find_joint("slide"), A0 = m.find_joint("A0");
  const double c = std::hypot(0.1, 0.12);
  const double x_lo = std::sqrt(0.09 - (c + 0.08) * (c + 0.08));
  const double x_hi = std::sqrt(0.09 - (c - 0.08) * (c - 0.08));
  m.design_positions = {position("s1", slide, 0.2), position("s2", slide, 0.25),
                        position("s3", slide, 0.15)};  // s3: below x_lo, cannot close
  const ValidationReport rep = validate_design_positions(m, any_index());
  ASSERT_EQ(rep.positions.size(), 3u);
  EXPECT_FALSE(rep.input_angular);
  EXPECT_FALSE(rep.positions[2].assembles);
  EXPECT_FALSE(rep.pass());
  EXPECT_EQ(rep.circuits, 0);  // not every position assembles: no trace
  m.design_positions.pop_back();
  const ValidationReport ok = validate_design_positions(m, any_index());
  EXPECT_TRUE(ok.pass());
  EXPECT_EQ(ok.circuits, 1);
  ASSERT_EQ(ok.singular_points.size(), 2u);
  for (const PositionReport& pr : ok.positions) {
    ASSERT_TRUE(pr.assembles) << pr.assembly_message;
    const double x = joint_coordinate(m, slide, pr.q);
    // The crank angle φ there satisfies (M2): x_C(φ) = x.
    const double phi = joint_coordinate(m, A0, pr.q);
    const double by = 0.1 + 0.08 * std::cos(phi), bz = 0.12 + 0.08 * std::sin(phi);
    EXPECT_NEAR(std::sqrt(0.09 - by * by - bz * bz), x, 1e-12) << pr.name;
    ASSERT_TRUE(pr.singular_distance.has_value());
    EXPECT_NEAR(*pr.singular_distance, std::min(x - x_lo, x_hi - x), 1e-10) << pr.name;
    EXPECT_NEAR(*pr.singular_input, x - x_lo < x_hi - x ? x_lo : x_hi, 1e-10) << pr.name;
  }
}

// ---- Bennett -----------------------------------------------------------------------------------

// θ1 = 20°, 75°, 140°: θ2 from tan(θ1/2) tan(θ2/2) = sin 45°/sin 15°; DOF 1 and 3 redundant
// equations at every position (docs/spatial.md §4.2); σ_min of rank 17 against differences.
TEST(SpatialValidate, BennettPositionsClosureAndThreeRedundantEquations) {
  Model m = test::load_bundled("bennett");
  const int J1 = m.find_joint("J1"), J2 = m.find_joint("J2");
  const double K = std::sin(45.0 * kDeg) / std::sin(15.0 * kDeg);
  const double t1[3] = {20.0, 75.0, 140.0};
  m.design_positions.clear();
  for (double t : t1)
    m.design_positions.push_back(
        position(std::to_string(static_cast<int>(t)) + "deg", J1, t * kDeg));
  const ValidationReport rep = validate_design_positions(m);
  ASSERT_EQ(rep.positions.size(), 3u);
  EXPECT_EQ(rep.generic_rank, 17);
  EXPECT_EQ(rep.circuits, 1);
  EXPECT_TRUE(rep.pass());
  for (size_t k = 0; k < 3; ++k) {
    const PositionReport& pr = rep.positions[k];
    ASSERT_TRUE(pr.assembles) << pr.assembly_message;
    EXPECT_EQ(pr.dof, 1);
    EXPECT_EQ(pr.rank, 17);
    EXPECT_EQ(pr.redundant.size(), 3u);
    const double theta2 = 2.0 * std::atan(K / std::tan(0.5 * t1[k] * kDeg));
    EXPECT_NEAR(wrap(joint_coordinate(m, J2, pr.q) - theta2), 0.0, 1e-9) << pr.name;
    expect_unit_quaternions(m, pr.q);
    const DifferenceJacobian J = difference_jacobian(m, pr.q, {J1});
    const VecX s = scaled_singular_values(m, J.Et);
    EXPECT_LT(s(17) / s(0), 1e-8);  // rank 17 of 20 rows
    EXPECT_NEAR(pr.singular.sigma_min, s(16) / s(0), 1e-7 * s(16) / s(0)) << pr.name;
  }
  EXPECT_EQ(rep.positions[1].q.size(), m.nq);
}

// ---- spatial targets ---------------------------------------------------------------------------

// mechanisms/rssr.yaml with its design positions replaced by `positions` (YAML, file units mm and
// deg), loaded through the reader.
Model rssr_with_positions(const std::string& positions) {
  std::ifstream in(test::bundled_file("rssr"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find("design_positions:");
  const size_t end = text.find("analysis:", at);
  EXPECT_NE(at, std::string::npos);
  text =
      text.substr(0, at).append("design_positions:\n").append(positions).append(text.substr(end));
  const test::TempDir dir("orthomech_spatial_target_");
  const std::string file = (dir.path / "rssr-targets.yaml").string();
  std::ofstream(file) << text;
  return load_mechanism(file);
}

std::string num(double v) {  // every digit: the test knows exactly what the file holds
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}
std::string vec(const Vec3& v) {
  return std::string("[") + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + "]";
}

// The RSSR's points from (M1), mm: A on the crank, B on the rocker (branch `sign` of φ).
Vec3 crank_A(double theta) { return 1e3 * Vec3(r1 * std::cos(theta), r1 * std::sin(theta), 0.0); }
double rocker_root(double theta, double sign) {
  const M1 m(theta);
  return std::atan2(m.Q, m.P) + sign * std::acos(-m.S / std::hypot(m.P, m.Q));
}
Vec3 rocker_B(double phi) { return 1e3 * Vec3(p, r2 * std::cos(phi), h + r2 * std::sin(phi)); }

// Targets at θ = 60°, written in the test from (M1): rocker.B at its closed-form position
// (met: error ≈ 0), 2 mm above it (missed by exactly 2 mm); the rocker's whole orientation
// (body x along B0→B, z along world x: its frame at φ) met, and turned 3° about world x (missed
// by 3°); the coupler's x axis along A→B (met) and along world z (missed by the angle between
// A→B and z, computed here; its point coupler.B at B pins the assembly mode, as a direction alone
// picks the mode nearest it); the other root of (M1) as target picks that assembly mode.
TEST(SpatialValidate, TargetsMetAndMissedAgainstTheClosedFormM1) {
  const double theta = 60.0 * kDeg;
  const double phi = rocker_root(theta, 1.0), phi2 = rocker_root(theta, -1.0);
  const Vec3 A = crank_A(theta), B = rocker_B(phi), B2 = rocker_B(phi2);
  const Vec3 up(0.0, 0.0, 2.0);
  auto rocker_axes = [&](double f) {
    return std::string("{x: ") + vec(Vec3(0.0, std::cos(f), std::sin(f))) + ", z: [1, 0, 0]}";
  };
  const Vec3 AB = (B - A).normalized();
  const std::string pos =
      std::string("  - {name: met, inputs: {A0: 60}, target: {point: rocker.B, at: ") + vec(B) +
      ", tolerance: 0.001}}\n"
      "  - {name: high, inputs: {A0: 60}, target: {point: rocker.B, at: " +
      vec(B + up) +
      ", tolerance: 1}}\n"
      "  - {name: frame, inputs: {A0: 60}, target: {point: rocker.B, at: " +
      vec(B) + ", orientation: " + rocker_axes(phi) +
      ", angle_tolerance: 0.01}}\n"
      "  - {name: turned, inputs: {A0: 60}, target: {point: rocker.B, at: " +
      vec(B) + ", orientation: " + rocker_axes(phi + 3.0 * kDeg) +
      ", angle_tolerance: 1}}\n"
      "  - {name: along, inputs: {A0: 60}, target: {point: coupler.A, at: " +
      vec(A) + ", direction: {body: [1, 0, 0], world: " + vec(AB) +
      "}, angle_tolerance: 0.01}}\n"
      "  - {name: up, inputs: {A0: 60}, target: {point: coupler.B, at: " +
      vec(B) +
      ", tolerance: 0.001, direction: {body: [1, 0, 0], world: [0, 0, 1]}, angle_tolerance: 1}}\n"
      "  - {name: other, inputs: {A0: 60}, target: {point: rocker.B, at: " +
      vec(B2) + ", tolerance: 0.001}}\n";
  const Model m = rssr_with_positions(pos);
  ASSERT_EQ(m.design_positions.size(), 7u);
  const ValidationReport rep = validate_design_positions(m, any_index());
  ASSERT_EQ(rep.positions.size(), 7u);
  for (const PositionReport& pr : rep.positions) {
    ASSERT_TRUE(pr.assembles) << pr.name << ": " << pr.assembly_message;
    ASSERT_TRUE(pr.target_error.has_value()) << pr.name;
  }
  auto at = [&](const char* name) -> const PositionReport& {
    for (const PositionReport& pr : rep.positions)
      if (pr.name == name) return pr;
    throw std::runtime_error(name);
  };
  constexpr double kPos = 1e-9;  // m: the assembled pose to 1e-12, the closed form to round-off
  constexpr double kAng = 1e-9;  // rad
  // Position targets.
  EXPECT_LT(*at("met").target_error, kPos);
  EXPECT_TRUE(at("met").target_met);
  EXPECT_FALSE(at("met").target_angle_error.has_value());
  EXPECT_TRUE(at("met").pass()) << at("met").failures.at(0);
  EXPECT_NEAR(*at("high").target_error, 2e-3, kPos);
  EXPECT_FALSE(at("high").target_met);
  ASSERT_FALSE(at("high").failures.empty());
  EXPECT_NE(at("high").failures[0].find("target missed by 2 mm (tolerance 1 mm)"),
            std::string::npos)
      << at("high").failures[0];
  // Orientation targets: the rotation angle between the rocker's frame and the target.
  ASSERT_TRUE(at("frame").target_angle_error.has_value());
  EXPECT_LT(*at("frame").target_angle_error, kAng);
  EXPECT_TRUE(at("frame").target_met);
  ASSERT_TRUE(at("turned").target_angle_error.has_value());
  EXPECT_NEAR(*at("turned").target_angle_error, 3.0 * kDeg, kAng);
  EXPECT_LT(*at("turned").target_error, kPos);  // the point is met, the orientation is not
  EXPECT_FALSE(at("turned").target_met);
  ASSERT_FALSE(at("turned").failures.empty());
  EXPECT_NE(at("turned").failures[0].find("target orientation missed by 3 deg (tolerance 1 deg)"),
            std::string::npos)
      << at("turned").failures[0];
  // Direction targets: the coupler's x axis runs A→B.
  EXPECT_LT(*at("along").target_angle_error, kAng);
  EXPECT_TRUE(at("along").target_met);
  const double to_z = std::acos(AB.z());
  EXPECT_NEAR(*at("up").target_angle_error, to_z, kAng);
  EXPECT_EQ(at("up").target_met, to_z <= 1.0 * kDeg);
  EXPECT_FALSE(at("up").target_met);
  // The other root of (M1): the target picks that assembly mode.
  const PositionReport& o = at("other");
  EXPECT_LT(*o.target_error, kPos);
  EXPECT_TRUE(o.target_met);
  EXPECT_NEAR(wrap(joint_coordinate(m, m.find_joint("B0"), o.q) - phi2), 0.0, 1e-9);
  EXPECT_NE(o.mode, at("met").mode);
  EXPECT_GE(o.modes, 2);
}

// ---- Sutherland–Roth transmission index --------------------------------------------------------

// TI = |a·((p − o) × s)| / |a × (p − o)| written in the test from (M1): a = world x (the rocker
// axis), o = B0, p = B, s = (B − A)/|B − A|.
double rssr_index(double theta) {
  const Vec3 A = crank_A(theta), B = rocker_B(rocker(theta));
  const Vec3 r = B - 1e3 * Vec3(p, 0.0, h), s = (B - A).normalized(), a = Vec3::UnitX();
  return std::abs(a.dot(r.cross(s))) / a.cross(r).norm();
}

TEST(SpatialValidate, RssrTransmissionIndexAgainstTheClosedFormM1) {
  Model m = test::load_bundled("rssr");
  const int A0 = m.find_joint("A0");
  m.design_positions.clear();
  for (int k = 0; k < 8; ++k)
    m.design_positions.push_back(
        position(std::string("t").append(std::to_string(45 * k)), A0, 45.0 * k * kDeg));
  const std::vector<SpatialTransmissionLoop> loops = find_spatial_transmission_loops(m, A0);
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_EQ(loops[0].type, "RSUR");
  EXPECT_FALSE(loops[0].planar);
  EXPECT_FALSE(loops[0].prismatic_output);
  const ValidationReport rep = validate_design_positions(m);
  EXPECT_EQ(rep.not_applicable.size(), 3u);  // the planar checks only
  double lowest = 2.0;
  std::string lowest_at;
  for (int k = 0; k < 8; ++k) {
    const PositionReport& pr = rep.positions[static_cast<size_t>(k)];
    ASSERT_TRUE(pr.assembles) << pr.name;
    ASSERT_EQ(pr.spatial_loops.size(), 1u);
    EXPECT_EQ(pr.spatial_loops[0].joints, "A0-A-B-B0");
    EXPECT_EQ(pr.spatial_loops[0].type, "RSUR");
    const double ti = rssr_index(45.0 * k * kDeg);
    EXPECT_NEAR(pr.spatial_loops[0].index, ti, 1e-9) << pr.name;
    EXPECT_EQ(pr.spatial_loops[0].ok, ti >= 0.5) << pr.name;
    if (ti < lowest) lowest = ti, lowest_at = pr.name;
  }
  ASSERT_TRUE(rep.min_transmission_index.has_value());
  EXPECT_NEAR(*rep.min_transmission_index, lowest, 1e-9);
  EXPECT_EQ(rep.min_transmission_index_at, lowest_at);
  EXPECT_DOUBLE_EQ(rep.transmission_index_bound, 0.5);  // sin 30°
  // A bound above the largest index fails every position, naming the loop.
  ValidateOptions strict;
  strict.min_transmission_index = 0.9999;
  const ValidationReport fail = validate_design_positions(m, strict);
  EXPECT_FALSE(fail.pass());
  for (const PositionReport& pr : fail.positions) {
    EXPECT_FALSE(pr.spatial_loops[0].ok) << pr.name;
    const bool named = std::any_of(pr.failures.begin(), pr.failures.end(), [](const auto& f) {
      return f.find("transmission index") != std::string::npos &&
             f.find("A0-A-B-B0 (RSUR") != std::string::npos;
    });
    EXPECT_TRUE(named) << pr.name;
  }
}

// The planar four-bar built with spatial revolutes (mechanisms/crank-rocker-3d.yaml): TI = sin μ,
// μ the transmission angle validate reports for the planar file at the same crank angles.
TEST(SpatialValidate, CrankRocker3dTransmissionIndexIsSineOfThePlanarTransmissionAngle) {
  Model m = test::load_bundled("crank-rocker-3d");
  Model planar = test::load_bundled("crank-rocker");
  const int A0 = m.find_joint("A0"), pA0 = planar.find_joint("A0");
  m.design_positions.clear();
  planar.design_positions.clear();
  for (int k = 0; k < 6; ++k) {
    const std::string name = std::string("c").append(std::to_string(60 * k));
    m.design_positions.push_back(position(name, A0, (60.0 * k + 10.0) * kDeg));
    planar.design_positions.push_back(position(name, pA0, (60.0 * k + 10.0) * kDeg));
  }
  const ValidationReport rep = validate_design_positions(m);
  const ValidationReport prep = validate_design_positions(planar);
  for (size_t k = 0; k < 6; ++k) {
    const PositionReport& pr = rep.positions[k];
    const PositionReport& pp = prep.positions[k];
    ASSERT_TRUE(pr.assembles && pp.assembles) << pr.name;
    ASSERT_EQ(pr.spatial_loops.size(), 1u);
    EXPECT_EQ(pr.spatial_loops[0].type, "RRRR");
    EXPECT_EQ(pr.spatial_loops[0].joints, "A0-A-B-B0");
    ASSERT_EQ(pp.four_bars.size(), 1u);
    EXPECT_NEAR(pr.spatial_loops[0].index, std::sin(pp.four_bars[0].transmission), 1e-9) << pr.name;
    EXPECT_EQ(pr.spatial_loops[0].ok, pp.four_bars[0].ok) << pr.name;
  }
  EXPECT_TRUE(planar.dimension == 2 && find_spatial_transmission_loops(planar, pA0).empty());
}

// The spatial slider-crank (RSUP): TI = |x·s| = x_C / 0.3 from (M2) (C = (x_C, 0, 0), rod 0.3 m).
TEST(SpatialValidate, SliderCrankTransmissionIndexFromM2) {
  const Model m = test::load_bundled("spatial-slider-crank");
  const int A0 = m.find_joint("A0");
  const ValidationReport rep = validate_design_positions(m);
  ASSERT_EQ(rep.positions.size(), 3u);
  for (const PositionReport& pr : rep.positions) {
    ASSERT_TRUE(pr.assembles) << pr.name;
    ASSERT_EQ(pr.spatial_loops.size(), 1u);
    EXPECT_EQ(pr.spatial_loops[0].type, "RSUP");
    const double phi = joint_coordinate(m, A0, pr.q);
    const double by = 0.1 + 0.08 * std::cos(phi), bz = 0.12 + 0.08 * std::sin(phi);
    EXPECT_NEAR(pr.spatial_loops[0].index, std::sqrt(0.09 - by * by - bz * bz) / 0.3, 1e-10)
        << pr.name;
  }
}

// The RSSR with its coupler replaced by a distance row between crank.A and rocker.B (an S–S rod
// of 420 mm: the same kinematics): the loop "RDR", the index of (M1).
TEST(SpatialValidate, DistanceRowCouplerHasTheRssrIndex) {
  std::ifstream in(test::bundled_file("rssr"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto cut = [&](const std::string& from, const std::string& to) {
    const size_t a = text.find(from), b = text.find(to, a);
    ASSERT_NE(a, std::string::npos);
    ASSERT_NE(b, std::string::npos);
    text.erase(a, b - a);
  };
  cut("  - name: coupler", "  - name: rocker");
  cut("  - {name: A, type: spherical", "  - {name: B0,");
  const size_t j = text.find("  - {name: B0,");
  text.insert(j, "  - {name: rod, type: distance, connects: [crank.A, rocker.B], length: 420}\n");
  const test::TempDir dir("orthomech_spatial_rdr_");
  const std::string file = (dir.path / "rdr.yaml").string();
  std::ofstream(file) << text;
  Model m = load_mechanism(file);
  const int A0 = m.find_joint("A0");
  m.design_positions = {position("t0", A0, 0.0), position("t90", A0, 90.0 * kDeg)};
  const ValidationReport rep = validate_design_positions(m);
  for (size_t k = 0; k < 2; ++k) {
    const PositionReport& pr = rep.positions[k];
    ASSERT_TRUE(pr.assembles) << pr.name << ": " << pr.assembly_message;
    ASSERT_EQ(pr.spatial_loops.size(), 1u);
    EXPECT_EQ(pr.spatial_loops[0].type, "RDR");
    EXPECT_EQ(pr.spatial_loops[0].joints, "A0-rod-B0");
    EXPECT_NEAR(pr.spatial_loops[0].index, rssr_index(90.0 * static_cast<double>(k) * kDeg), 1e-9);
  }
}

// The same index in its velocity form (an independent formulation): |a·(r × s)| / |a × r| =
// |t·s|, t the unit velocity of B on its circle about the rocker axis, (0, −sin φ, cos φ) from
// (M1). Driven from the rocker (input B0) the loop turns round: B0-B-A-A0 ("RUSR"), the output
// the crank about z through A0, TI = |t_A·s| with t_A = (−sin θ, cos θ, 0), θ the root of (M1)
// for the given φ on the branch the position is on (cos θ, sin θ from the linear equation
// −2 r1 r2 cos φ sin θ − 2 p r1 cos θ = −(2 h r2 sin φ + p² + r1² + r2² + h² − L²)).
TEST(SpatialValidate, RssrTransmissionIndexVelocityFormAndRockerInput) {
  for (int k = 0; k < 8; ++k) {
    const double theta = 45.0 * k * kDeg, phi = rocker(theta);
    const Vec3 A = crank_A(theta), B = rocker_B(phi), s = (B - A).normalized();
    EXPECT_NEAR(rssr_index(theta), std::abs(Vec3(0.0, -std::sin(phi), std::cos(phi)).dot(s)),
                1e-12);
  }
  Model m = test::load_bundled("rssr");
  const int A0 = m.find_joint("A0"), B0 = m.find_joint("B0");
  m.design_positions = {position("r150", B0, 150.0 * kDeg), position("r170", B0, 170.0 * kDeg),
                        position("r200", B0, 200.0 * kDeg)};
  const ValidationReport rep = validate_design_positions(m, any_index());
  for (const PositionReport& pr : rep.positions) {
    ASSERT_TRUE(pr.assembles) << pr.name << ": " << pr.assembly_message;
    ASSERT_EQ(pr.spatial_loops.size(), 1u);
    EXPECT_EQ(pr.spatial_loops[0].joints, "B0-B-A-A0");
    EXPECT_EQ(pr.spatial_loops[0].type, "RUSR");
    const double phi = joint_coordinate(m, B0, pr.q);
    // a sin θ + b cos θ = c: θ = atan2(a, b) ± acos(c / √(a² + b²)).
    const double a = -2.0 * r1 * r2 * std::cos(phi), b = -2.0 * p * r1;
    const double c = -(2.0 * h * r2 * std::sin(phi) + p * p + r1 * r1 + r2 * r2 + h * h - Lc * Lc);
    const double base = std::atan2(a, b), off = std::acos(c / std::hypot(a, b));
    const double model_theta = joint_coordinate(m, A0, pr.q);
    const double theta =
        std::abs(wrap(base + off - model_theta)) < std::abs(wrap(base - off - model_theta))
            ? base + off
            : base - off;
    EXPECT_NEAR(wrap(theta - model_theta), 0.0, 1e-9) << pr.name;  // on (M1)
    const Vec3 A = crank_A(theta), B = rocker_B(phi), s = (B - A).normalized();
    EXPECT_NEAR(pr.spatial_loops[0].index,
                std::abs(Vec3(-std::sin(theta), std::cos(theta), 0.0).dot(s)), 1e-9)
        << pr.name;
  }
}

// No transmission loop (Bennett: four revolutes with skew axes): "not applicable", no index.
TEST(SpatialValidate, BennettHasNoTransmissionLoop) {
  const Model m = test::load_bundled("bennett");
  EXPECT_TRUE(find_spatial_transmission_loops(m, -1).empty());
  const ValidationReport rep = validate_design_positions(m);
  ASSERT_EQ(rep.not_applicable.size(), 4u);
  EXPECT_NE(rep.not_applicable[3].find("Sutherland & Roth"), std::string::npos);
  EXPECT_FALSE(rep.min_transmission_index.has_value());
  for (const PositionReport& pr : rep.positions) EXPECT_TRUE(pr.spatial_loops.empty());
}

}  // namespace
}  // namespace orthomech

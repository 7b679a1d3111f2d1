// validate on spatial mechanisms (issue 13 item 2) against independent oracles:
//  - RSSR positions against the closed form (M1) of spatial.md §4.1 (rocker angle φ(θ)), its dead
//    points of the rocker input from dφ/dθ = 0 of (M1), solved in the test by bisection;
//  - Bennett positions against the closure tan(θ1/2) tan(θ2/2) = sin((β+α)/2)/sin((β−α)/2) and its
//    DOF 1 with 3 redundant equations at every position (spatial.md §4.2);
//  - σ_min and η against an SVD of the Jacobian built in the test by central differences of f and
//    of the input through q ⊕ h·e_k (integrate_positions), with the mass matrix assembled in the
//    test from the bodies' masses and inertia tensors;
//  - the idle spin of an S–S coupler (spatial.md §4.1): held by the row e_ωx of the coupler
//    (its long axis), written in the test.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <numbers>

#include "orthomech/analysis/validate.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
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

DesignPosition position(const std::string& name, int joint, double value) {
  DesignPosition d;
  d.name = name;
  d.inputs = {{joint, value}};
  return d;
}

// The mass matrix from the bodies' data (spatial.md §1.4: M_b = diag(m I₃, J)).
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
  const ValidationReport rep = validate_design_positions(m);
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
// (spatial.md §4.1): DOF 2, one of them idle, so one input fixes the position; η is taken with
// the spin held (the row e_ωx of the coupler, its long axis, written here) and the circuit closes.
TEST(SpatialValidate, IdleSpinIsReportedAndHeld) {
  Model m = test::load_bundled("rssr");
  const int A0 = m.find_joint("A0"), B0 = m.find_joint("B0");
  std::get<SpatialJoint>(m.joints[static_cast<size_t>(m.find_joint("B"))].kind).type =
      SpatialJointType::spherical;
  finalize_model(m);
  m.design_positions = {position("p30", A0, 30.0 * kDeg), position("p120", A0, 120.0 * kDeg)};
  const ValidationReport rep = validate_design_positions(m);
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

// With the slide as the input, the dead points are the extremes of (M2) (spatial.md §4.4):
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
  const ValidationReport rep = validate_design_positions(m);
  ASSERT_EQ(rep.positions.size(), 3u);
  EXPECT_FALSE(rep.input_angular);
  EXPECT_FALSE(rep.positions[2].assembles);
  EXPECT_FALSE(rep.pass());
  EXPECT_EQ(rep.circuits, 0);  // not every position assembles: no trace
  m.design_positions.pop_back();
  const ValidationReport ok = validate_design_positions(m);
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
// equations at every position (spatial.md §4.2); σ_min of rank 17 against differences.
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

// A target cannot be given in a spatial mechanism (the reader refuses it; a Model built in code
// with one is API misuse).
TEST(SpatialValidate, TargetInASpatialModelIsRefused) {
  Model m = test::load_bundled("rssr");
  DesignTarget t;
  t.point.body = 0;
  m.design_positions[0].target = t;
  EXPECT_THROW((void)validate_design_positions(m), std::invalid_argument);
}

}  // namespace
}  // namespace orthomech

// Initial conditions (issue 4): `assemble` (Ipopt projection) and u = α u₀, against
//  - the published consistent angles of Andrews' squeezer at t = 0 (references.md §1: Test Set
//    for IVP Solvers, problem `andrews`; Hairer & Wanner II §VII.7);
//  - closed-form circle intersections (the two assembly modes of a four-bar);
//  - the closed-form closure gap of a four-bar whose links are too short;
//  - central differences of Eᵀλ (the exact Hessian identity (L2) used by the solver);
//  - the SVD null space of Eᵀ (mass-metric closest admissible velocity).
#include "orthomech/analysis/assembly.hpp"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/mechanism_writer.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/projection/chart_engine.hpp"
#include "support/andrews_reference.hpp"
#include "support/fixtures.hpp"
#include "support/zoo.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace orthomech {
namespace {

constexpr double kPi = std::numbers::pi;
// The t = 0 angles are published to 30 digits; the issue asks for 1e-12 rad.
constexpr double kAndrewsTol = 1e-12;
// Closed-form positions of small test linkages (1–10 m): rounding level of the solver.
constexpr double kClosedFormTol = 1e-11;

double measure(const Model& m, const std::string& name, const VecX& q) {
  const int k = m.find_measure(name);
  return evaluate_measure(m, m.measures.at(static_cast<size_t>(k)), q, nullptr, nullptr);
}

TEST(Assembly, Andrews_RoughAnglesWithBetaLocked_ReproducePublishedT0) {
  Model m = test::load_bundled("andrews-squeezer");
  // Rough design poses: angles rounded to 0.1 rad, positions to 1 mm.
  test::andrews::round_design_poses(m);
  const VecX q0 = m.design_q();
  AssemblyOptions o;
  // Published consistent values at t = 0 (references.md §1).
  const auto& published = test::andrews::kAnglesT0;
  o.locks.push_back({m.find_joint("O"), published[0]});
  const AssemblyResult r = assemble(m, q0, o);
  ASSERT_EQ(r.status, AssemblyStatus::assembled) << r.message;
  EXPECT_LE(r.residual, 1e-12);
  for (size_t k = 0; k < published.size(); ++k)
    EXPECT_NEAR(measure(m, test::andrews::kNames[k], r.q), published[k], kAndrewsTol)
        << test::andrews::kNames[k];
  EXPECT_GT(r.distance, 0.0);
  ASSERT_EQ(r.bodies.size(), m.bodies.size());
  ASSERT_EQ(r.joints.size(), m.joints.size());
  for (const JointResidual& j : r.joints) EXPECT_LE(j.residual, 1e-12) << j.joint;
}

TEST(Assembly, Unlocked_DisplacementIsMassOrthogonalToTheManifold) {
  // Optimality of (A1) without locks: q − q₀ is M-orthogonal to every admissible direction,
  // Nᵀ M (q − q₀) = 0 with N a basis of null(Eᵀ(q)) from the SVD (the paper's projection).
  for (const char* name : {"andrews-squeezer", "crank-rocker", "watt-six-bar"}) {
    Model m = test::load_bundled(name);
    for (Body& b : m.bodies) b.design_pose.z() += 0.05;  // 3° off everywhere
    const VecX q0 = m.design_q();
    const AssemblyResult r = assemble(m, q0);
    ASSERT_EQ(r.status, AssemblyStatus::assembled) << name << ": " << r.message;
    MatX Et(m.nc, m.n), M(m.n, m.n);
    compute_constraint_jacobian(m, r.q, Et);
    compute_mass_matrix(m, r.q, M);
    Eigen::JacobiSVD<MatX> svd(Et, Eigen::ComputeFullV);
    svd.setThreshold(1e-9);
    const MatX N = svd.matrixV().rightCols(m.n - svd.rank());
    const VecX g = M * (r.q - q0);
    // ~1e-17 after the KKT polish; the first-order Gauss–Newton projection gives 1e-4…1e-3 here.
    EXPECT_LE((N.transpose() * g).norm(), 1e-12 * g.norm()) << name;
    EXPECT_LE(r.residual, 1e-12) << name;
  }
}

TEST(Assembly, AlreadyAssembled_ReturnedBitForBit) {
  for (const char* name : {"andrews-squeezer", "crank-rocker", "slider-crank", "triple-crank"}) {
    const Model m = test::load_bundled(name);
    const VecX q = test::assembled_q(m);
    const AssemblyResult r = assemble(m, q);
    EXPECT_EQ(r.status, AssemblyStatus::unchanged) << name;
    ASSERT_EQ(r.q.size(), q.size());
    for (Eigen::Index k = 0; k < q.size(); ++k) EXPECT_EQ(r.q(k), q(k)) << name << " " << k;
    EXPECT_EQ(r.distance, 0.0);
  }
}

// A four-bar in SI: ground pivots A0 (0, 0), B0 (d, 0); crank a, coupler b, rocker c. Body
// frames: crank at A0 along A0→A; coupler at A along A→B; rocker at B0 along B0→B.
std::string four_bar_yaml(double a, double b, double c, double d, double crank, double coupler,
                          double rocker, const std::string& extra = "") {
  std::ostringstream s;
  s.precision(17);
  const double ax = a * std::cos(crank), ay = a * std::sin(crank);
  s << "orthomech: 1\nname: fb\nground:\n  points: {A0: [0, 0], B0: [" << d << ", 0]}\n"
    << "bodies:\n"
    << "  - {name: crank, mass: 1, inertia: 0.1, com: [" << a / 2 << ", 0], pose: [0, 0, " << crank
    << "], points: {A0: [0, 0], A: [" << a << ", 0]}}\n"
    << "  - {name: coupler, mass: 2, inertia: 0.3, com: [" << b / 2 << ", 0], pose: [" << ax << ", "
    << ay << ", " << coupler << "], points: {A: [0, 0], B: [" << b << ", 0]}}\n"
    << "  - {name: rocker, mass: 1.5, inertia: 0.2, com: [" << c / 2 << ", 0], pose: [" << d
    << ", 0, " << rocker << "], points: {B0: [0, 0], B: [" << c << ", 0]}}\n"
    << "joints:\n"
    << "  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]" << extra << "}\n"
    << "  - {name: A, type: revolute, connects: [crank.A, coupler.A]}\n"
    << "  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}\n"
    << "  - {name: B0, type: revolute, connects: [rocker.B0, ground.B0]}\n"
    << "measures:\n"
    << "  - {name: Bx, type: point, point: coupler.B, component: x}\n"
    << "  - {name: By, type: point, point: coupler.B, component: y}\n";
  return s.str();
}

// The two intersections of circle(A, b) and circle(B0, c) (closed form).
std::pair<Vec2, Vec2> circle_intersections(const Vec2& p0, double r0, const Vec2& p1, double r1) {
  const Vec2 d = p1 - p0;
  const double L = d.norm();
  const double x = (r0 * r0 - r1 * r1 + L * L) / (2 * L);
  const double h = std::sqrt(r0 * r0 - x * x);
  const Vec2 e = d / L, n(-e.y(), e.x());
  return {p0 + x * e + h * n, p0 + x * e - h * n};
}

TEST(Assembly, FourBar_BothAssemblyModes_MatchCircleIntersections) {
  const double a = 1.0, b = 3.0, c = 2.5, d = 3.2, theta = 0.7;
  const Vec2 A(a * std::cos(theta), a * std::sin(theta));
  const auto [B_up, B_down] = circle_intersections(A, b, Vec2(d, 0), c);
  // Guesses: the coupler drawn roughly toward each intersection (10° off, 5 cm off).
  int found = 0;
  for (const Vec2& B : {B_up, B_down}) {
    const double coupler = std::atan2(B.y() - A.y(), B.x() - A.x()) + 0.17;
    const double rocker = std::atan2(B.y(), B.x() - d) - 0.17;
    const Model m = parse_mechanism(four_bar_yaml(a, b, c, d, theta + 0.1, coupler, rocker), "fb");
    AssemblyOptions o;
    o.locks.push_back({m.find_joint("A0"), theta});
    const AssemblyResult r = assemble(m, m.design_q(), o);
    ASSERT_EQ(r.status, AssemblyStatus::assembled) << r.message;
    EXPECT_NEAR(measure(m, "Bx", r.q), B.x(), kClosedFormTol);
    EXPECT_NEAR(measure(m, "By", r.q), B.y(), kClosedFormTol);
    EXPECT_NEAR(joint_coordinate(m, m.find_joint("A0"), r.q), theta, kClosedFormTol);
    ++found;
  }
  EXPECT_EQ(found, 2);
  EXPECT_GT((B_up - B_down).norm(), 1.0);  // genuinely different modes
}

TEST(Assembly, LinksTooShort_CannotClose_NamesJointsAndClosedFormGap) {
  // a + b + c = 6 < d = 10: the best pose lays the links along A0B0; the closure gap is
  // d − (a + b + c) = 4 m, shared equally by the four joints (least squares: 1 m each).
  const Model m = parse_mechanism(four_bar_yaml(1, 2, 3, 10, 0.5, 0.2, 2.5), "short");
  const AssemblyResult r = assemble(m, m.design_q());
  ASSERT_EQ(r.status, AssemblyStatus::cannot_close) << r.message;
  EXPECT_NEAR(r.total_gap, 4.0, 1e-6);
  ASSERT_EQ(r.gaps.size(), 4u);
  for (const JointResidual& j : r.gaps) EXPECT_NEAR(j.gap, 1.0, 1e-6) << j.joint;
  for (const char* joint : {"'A0'", "'A'", "'B'", "'B0'"})
    EXPECT_NE(r.message.find(joint), std::string::npos) << r.message;
  // In the file's declared length unit (none declared: m).
  EXPECT_NE(r.message.find("total gap 4 m"), std::string::npos) << r.message;
}

TEST(Assembly, LockOutsideTheRockerRange_CannotClose) {
  // Crank-rocker: the rocker swings 64.62°…135.58° (mechanisms/crank-rocker.yaml); 20° is out.
  const Model m = test::load_bundled("crank-rocker");
  AssemblyOptions o;
  o.locks.push_back({m.find_joint("B0"), 20.0 * kPi / 180.0});
  const AssemblyResult r = assemble(m, m.design_q(), o);
  EXPECT_EQ(r.status, AssemblyStatus::cannot_close) << r.message;
  EXPECT_FALSE(r.gaps.empty());
  EXPECT_GT(r.total_gap, 1e-4);
  EXPECT_NE(r.message.find("locked"), std::string::npos);
}

TEST(Assembly, PrismaticLock_SliderCrankClosedForm) {
  // In-line slider-crank r = 50, l = 200 mm: wrist pin x = r cos θ + √(l² − r² sin² θ).
  const Model m = test::load_bundled("slider-crank");
  const int slide = m.find_joint("slide");
  ASSERT_GE(slide, 0);
  const double r = 0.05, l = 0.2, theta = 1.1;  // crank angle, design is 45°
  const double x =
      r * std::cos(theta) + std::sqrt(l * l - r * r * std::sin(theta) * std::sin(theta));
  AssemblyOptions o;
  o.locks.push_back({slide, x});
  const AssemblyResult res = assemble(m, m.design_q(), o);
  ASSERT_EQ(res.status, AssemblyStatus::assembled) << res.message;
  EXPECT_NEAR(measure(m, "crank_angle", res.q), theta, 1e-12);  // the branch of the drawing
  EXPECT_NEAR(joint_coordinate(m, slide, res.q), x, 1e-13);
  EXPECT_NEAR(measure(m, "piston_x", res.q), x, 1e-12);
}

TEST(Assembly, JointLimits_AreBounds) {
  // Drawn exactly assembled with the crank at 0.5 rad, but the crank is limited to [0.9, 1.2]:
  // the closest assembled pose inside the limits has the crank on the bound 0.9. Without the
  // limits the drawing is returned unchanged.
  const double a = 1.0, b = 3.0, c = 2.5, d = 3.2, theta = 0.5;
  const Vec2 A(a * std::cos(theta), a * std::sin(theta));
  const Vec2 B = circle_intersections(A, b, Vec2(d, 0), c).first;
  const double coupler = std::atan2(B.y() - A.y(), B.x() - A.x());
  const double rocker = std::atan2(B.y(), B.x() - d);
  const Model m = parse_mechanism(
      four_bar_yaml(a, b, c, d, theta, coupler, rocker, ", limits: [0.9, 1.2]"), "limited");
  ASSERT_TRUE(m.joints[0].limits.has_value());
  const AssemblyResult r = assemble(m, m.design_q());
  ASSERT_EQ(r.status, AssemblyStatus::assembled) << r.message;
  EXPECT_NEAR(joint_coordinate(m, 0, r.q), 0.9, 1e-9);
  AssemblyOptions free;
  free.use_limits = false;
  const AssemblyResult f = assemble(m, m.design_q(), free);
  EXPECT_EQ(f.status, AssemblyStatus::unchanged) << f.message;
}

TEST(Assembly, L2_ConvectiveTermIsTheHessianOfTheConstraints) {
  // Σλ_i ∇²f_i e_k = Dᵀ(q, e_k)ᵀ λ: compare with central differences of Eᵀ(q)ᵀλ (zoo: every
  // joint type, at a pose that is not assembled).
  const Model m = parse_mechanism(test::kZooYaml, "zoo");
  const VecX q = m.design_q();
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> dist(-1, 1);
  VecX lambda(m.nc);
  for (Eigen::Index i = 0; i < lambda.size(); ++i) lambda(i) = dist(gen);
  ConstraintWorkspace cws(m);
  State s(m);
  s.q = q;
  MatX Etp(m.nc, m.n), Etm(m.nc, m.n);
  const double h = 1e-6;
  for (int k = 0; k < m.n; ++k) {
    s.u.setZero();
    s.u(k) = 1.0;
    compute_constraints(m, s, cws);
    const VecX exact = cws.Dt.transpose() * lambda;
    VecX qp = q, qm = q;
    qp(k) += h;
    qm(k) -= h;
    compute_constraint_jacobian(m, qp, Etp);
    compute_constraint_jacobian(m, qm, Etm);
    const VecX fd = (Etp - Etm).transpose() * lambda / (2 * h);
    EXPECT_LE((exact - fd).cwiseAbs().maxCoeff(), 1e-7) << "column " << k;
  }
}

TEST(Assembly, L1_JointCoordinateHessianAgainstCentralDifferences) {
  // ∇²s of every revolute and prismatic joint coordinate of the zoo (prismatic J2 between two
  // moving bodies, J8 against the ground) against central differences of the gradient d(q).
  const Model m = parse_mechanism(test::kZooYaml, "zoo");
  const VecX q = m.design_q();
  VecX dp(m.n), dm(m.n);
  const double h = 1e-6;
  int prismatic = 0;
  for (int j = 0; j < static_cast<int>(m.joints.size()); ++j) {
    const auto& kind = m.joints[static_cast<size_t>(j)].kind;
    if (!std::holds_alternative<Revolute>(kind) && !std::holds_alternative<Prismatic>(kind))
      continue;
    prismatic += std::holds_alternative<Prismatic>(kind) ? 1 : 0;
    const MatX H = joint_coordinate_hessian(m, j, q);
    EXPECT_LE((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-14);
    for (int k = 0; k < m.nq; ++k) {
      VecX qp = q, qm = q;
      qp(k) += h;
      qm(k) -= h;
      dp.setZero();
      dm.setZero();
      compute_scalar(m, JointCoordinate{j}, qp, nullptr, dp);
      compute_scalar(m, JointCoordinate{j}, qm, nullptr, dm);
      const VecX fd = (dp - dm) / (2 * h);
      EXPECT_LE((H.col(k) - fd).cwiseAbs().maxCoeff(), 1e-8)
          << m.joints[static_cast<size_t>(j)].name << " column " << k;
    }
  }
  EXPECT_EQ(prismatic, 2);
}

TEST(Assembly, InitialVelocities_MassOrthogonalProjection) {
  // u = α u₀ equals the SVD-based mass-metric projection onto null(Eᵀ):
  // u* = N (Nᵀ M N)⁻¹ Nᵀ M u₀; T(u₀) = T(u) + T(βu₀).
  for (const char* name : {"crank-rocker", "andrews-squeezer", "triple-crank"}) {
    const Model m = test::load_bundled(name);
    const VecX q = test::assembled_q(m);
    std::mt19937 gen(11);
    std::uniform_real_distribution<double> dist(-1, 1);
    VecX u0(m.n);
    for (Eigen::Index i = 0; i < u0.size(); ++i) u0(i) = dist(gen);
    const VelocityProjection v = project_velocities(m, q, u0);
    MatX Et(m.nc, m.n), M(m.n, m.n);
    compute_constraint_jacobian(m, q, Et);
    compute_mass_matrix(m, q, M);
    EXPECT_LE((Et * v.u).cwiseAbs().maxCoeff(), 1e-10 * (1 + u0.norm())) << name;
    Eigen::JacobiSVD<MatX> svd(Et, Eigen::ComputeFullV);
    svd.setThreshold(1e-9);
    const MatX N = svd.matrixV().rightCols(m.n - svd.rank());
    const MatX H = N.transpose() * M * N;
    const VecX u_star = N * H.ldlt().solve(N.transpose() * M * u0);
    EXPECT_LE((v.u - u_star).cwiseAbs().maxCoeff(), 1e-9 * (1 + u0.norm())) << name;
    EXPECT_NEAR(v.kinetic_initial, v.kinetic + v.kinetic_removed, 1e-12 * v.kinetic_initial)
        << name;
  }
}

// Large models take the chart engine's sparse path (n ≥ ChartEngine::kSparseSelectFrom, a
// diagonal M): the N-four-bar N = 100 (n = 603) at a regular pose (E of full column rank) and at
// its change point (all links on the x axis: N redundant rows, DOF N + 1), and a 250-link chain
// (n_a = 250). Oracle, dense and independent of the charts: the mass-metric projection onto the
// null space of Eᵀ from an SVD, u* = N (Nᵀ M N)⁻¹ Nᵀ M u₀ (the test above).
TEST(Assembly, InitialVelocities_LargeModelsOnTheSparsePath) {
  struct Case {
    std::string name, yaml;
    int dof;
  };
  const std::vector<Case> cases{{"n-four-bar-100 at 1.1 rad", test::n_four_bar_yaml(100, 1.1), 1},
                                {"n-four-bar-100 flat", test::n_four_bar_yaml(100, 0.0), 101},
                                {"chain-250", test::pendulum_chain_yaml(250), 250}};
  for (const Case& c : cases) {
    const Model m = parse_mechanism(c.yaml, c.name + ".yaml");
    ASSERT_GE(m.n, ChartEngine::kSparseSelectFrom) << c.name;
    const VecX q = m.design_q();
    std::mt19937 gen(5);
    std::uniform_real_distribution<double> dist(-1, 1);
    VecX u0(m.n);
    for (Eigen::Index i = 0; i < u0.size(); ++i) u0(i) = dist(gen);
    const VelocityProjection v = project_velocities(m, q, u0);
    ASSERT_TRUE(v.ok) << c.name;
    MatX Et(m.nc, m.n), M(m.n, m.n);
    compute_constraint_jacobian(m, q, Et);
    compute_mass_matrix(m, q, M);
    EXPECT_LE((Et * v.u).cwiseAbs().maxCoeff(), 1e-10 * (1 + u0.norm())) << c.name;
    Eigen::BDCSVD<MatX> svd(Et, Eigen::ComputeFullV);
    svd.setThreshold(1e-9);
    ASSERT_EQ(m.n - svd.rank(), c.dof) << c.name;
    const MatX N = svd.matrixV().rightCols(c.dof);
    const MatX H = N.transpose() * M * N;
    const VecX u_star = N * H.ldlt().solve(N.transpose() * M * u0);
    EXPECT_LE((v.u - u_star).cwiseAbs().maxCoeff(), 1e-9 * (1 + u0.norm())) << c.name;
    EXPECT_NEAR(v.kinetic_initial, 0.5 * u0.dot(M * u0), 1e-12 * v.kinetic_initial) << c.name;
    EXPECT_NEAR(v.kinetic, 0.5 * u_star.dot(M * u_star), 1e-9 * v.kinetic_initial) << c.name;
    EXPECT_NEAR(v.kinetic_initial, v.kinetic + v.kinetic_removed, 1e-12 * v.kinetic_initial)
        << c.name;
  }
}

TEST(Assembly, ProjectWithLocks_CrankRockerAtP2) {
  const Model m = test::load_bundled("crank-rocker");
  VecX q = m.design_q();
  const int A0 = m.find_joint("A0");
  ASSERT_TRUE(project_with_locks(m, q, {{A0, 150.0 * kPi / 180.0}}));
  EXPECT_NEAR(joint_coordinate(m, A0, q), 150.0 * kPi / 180.0, 1e-12);
  // Coupler point P of design position p2 (file, rounded to 1e-6 mm).
  EXPECT_NEAR(measure(m, "P_x", q), -0.810374e-3, 1e-9);
  EXPECT_NEAR(measure(m, "P_y", q), 51.965546e-3, 1e-9);
}

}  // namespace
}  // namespace orthomech

namespace orthomech {
namespace {

// A measure's value locked on a planar file: the five-bar (DOF 2) with its point C at x = C_x + 5
// mm. The pose closes, C_x holds, and it is a KKT point of (A1): M (q − q₀) = Cᵀλ with
// C = ∂(f, C_x)/∂q by central differences (B̃ = I), independent of the code's derivatives; with
// 10 + 1 rows on 12 coordinates that is a real condition (one DOF is left to the metric).
TEST(Assembly, AMeasuresValueLockIsAKktPointOfTheMassMetric) {
  const Model m = test::load_bundled("five-bar");
  const int px = m.find_measure("C_x");
  const VecX q0 = m.design_q();
  const double target =
      evaluate_measure(m, m.measures[static_cast<size_t>(px)], q0, nullptr, nullptr) + 0.005;
  AssemblyOptions o;
  JointLock l;
  l.measure = px;
  l.value = target;
  o.locks.push_back(l);
  const AssemblyResult r = assemble(m, q0, o);
  ASSERT_EQ(r.status, AssemblyStatus::assembled) << r.message;
  const Measure& P = m.measures[static_cast<size_t>(px)];
  EXPECT_NEAR(evaluate_measure(m, P, r.q, nullptr, nullptr), target, 1e-12);
  VecX f(m.nc);
  compute_constraint_residual(m, r.q, f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-12);
  MatX C(m.nc + 1, m.nq);
  const double h = 1e-7;
  for (int k = 0; k < m.nq; ++k) {
    VecX qp = r.q, qm = r.q, fp(m.nc), fm(m.nc);
    qp(k) += h;
    qm(k) -= h;
    compute_constraint_residual(m, qp, fp);
    compute_constraint_residual(m, qm, fm);
    C.col(k).head(m.nc) = (fp - fm) / (2 * h);
    C(m.nc, k) = (evaluate_measure(m, P, qp, nullptr, nullptr) -
                  evaluate_measure(m, P, qm, nullptr, nullptr)) /
                 (2 * h);
  }
  MatX M(m.n, m.n);
  compute_mass_matrix(m, q0, M);
  const VecX g = M * (r.q - q0);
  const VecX lambda = C.transpose().completeOrthogonalDecomposition().solve(g);
  ASSERT_LT(C.rows(), m.nq);
  EXPECT_LT((C.transpose() * lambda - g).norm(), 1e-6 * g.norm());
  EXPECT_GT((r.q - q0).norm(), 1e-4);  // it moved
}

}  // namespace
}  // namespace orthomech

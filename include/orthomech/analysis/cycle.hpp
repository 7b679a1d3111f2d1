#pragma once
// Kinetostatics of a driven mechanism over a cycle (docs/design.md §6, issue 3).
//
// A driver prescribes one input s(q) (a joint coordinate) as a function of time. With d its
// Jacobian row and F the dual-form basis of admissible velocities (n_a = 1):
//   (dᵀF) v = ṡ                                   → v, u = F v                          (C1)
//   (dᵀF) v̇ = s̈ − ḋu − dᵀḞ v                       → v̇, u̇ = F v̇ + Ḟ v                    (C2)
//   (Fᵀd) τ = H v̇ + Fᵀ(M Ḟ v + Ṁ u − Q̂)            → τ, the drive force/torque           (C3)
//   E λ = R = M u̇ + Ṁ u − Q̂ − d τ                  → λ, minimum-norm                     (C4)
// (C3) is Fᵀ of the equation of motion M u̇ + Ṁu = Q̂ + dτ + Eλ (Fᵀ E = 0); (C4) is the rest. A
// reaction component cᵀλ is unique iff c ⟂ null(E) (docs/design.md §3); with redundant constraints
// λ is the minimum-norm solution and the other components are reported as indeterminate.
// dᵀF → 0 is a dead point of the driver: it is located (bisection on the input) and reported,
// never divided by.
//
// Idle degrees of freedom (Mobility::idle: a body's own motion that moves no other body, e.g. the
// spin of a coupler between two spherical joints about the line through them; docs/spatial.md §4.1,
// §6.5) are held at zero rate instead of being left to the driver: with I the idle rows
// (idle_rows: vᵀM for each idle motion v, so that the held velocity is mass-orthogonal to it)
// and F the basis of null(Eᵀ) (n_a = 1 + k columns), the held basis is F z with (I F) z = 0 and
// (C1)–(C4) hold with F z for F. Accelerations keep I u̇ + İ u = 0 (İ u by central differences of
// the rows' span along u, (I1)); the forces μ that hold the idle motions, (I F)ᵀ μ = Fᵀ(R − d τ),
// are not joint reactions: E λ = R − d τ − Iᵀ μ. They vanish when the motion is idle
// dynamically too (a coupler with its centre of mass on the line of its joints and an inertia
// symmetric about it: spin held at zero needs no moment); DrivenPoint::idle_hold reports them.
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cstddef>
#include <functional>
#include <iterator>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "orthomech/analysis/friction.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/reactions.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/model/state.hpp"
#include "orthomech/projection/workspace.hpp"
#include "orthomech/run_control.hpp"

namespace orthomech {

// From this many coordinates on, the position corrector of `cycle` keeps the Jacobian of a
// structurally sparse model in compressed form (DrivenWorkspace::J_sparse): below it the dense LU
// is cheap. (300 until 2026-11-29; lowered with kRatedSparseFrom: the dense path of the driven
// N-four-bar took 0.12 s at N = 30, n = 183, and 0.29 s at N = 40, the sparse one 0.04 s.)
inline constexpr int kSparseJacobianFrom = 100;

struct CycleOptions {
  // joint and law s(t): constant speed (a full turn of a revolute, or start → end), harmonic
  // (one period 1/f); polynomial laws have no cycle and are refused.
  Driver driver;
  bool full_cycle = true;  // one full cycle (else the range start → end, constant speed)
  double start = 0.0;      // used when !full_cycle or use_start: input range [start, end] (SI)
  double end = 0.0;
  bool use_start = false;  // start at `start` instead of the design position's input
  int steps = 360;
  double dead_point_tolerance = 1e-10;  // input interval of the dead-point bisection (SI)
  // At a dead point (a fold of the input) pass it along the configuration curve and drive the
  // input back (constant-speed drivers): a rocker-driven double-rocker then sweeps its whole
  // closed curve, both assembly branches, until it returns to its start.
  bool reverse_at_dead_point = false;
  // The run's bounds (orthomech/run_control.hpp): a wall-clock limit, an interrupt flag, and a
  // progress callback with the fraction of the sweep done. The positions themselves are bounded
  // by `steps` (and 4 × steps for a reversing sweep); a bound met ends the sweep with status
  // `stopped` and the positions reached so far.
  RunControl control;
  // Take the positions next to change points from the branch (CycleResult::bridges).
  bool bridge_change_points = true;
  // From this many coordinates on, the corrector's Jacobian of a structurally sparse model is
  // sparse (kSparseJacobianFrom; tests set 0 to run small models on that path).
  int sparse_jacobian_from = kSparseJacobianFrom;
};

// How far the initial projection moved a body from its drawn pose (with the driven joint held at
// its drawn value). Listed, and warned about, when above kStartMoveTolerance × the mechanism's
// size (the largest distance of a drawn body pose from the origin, at least 1 mm) or
// kStartTurnTolerance rad: a rounded pose moves less, a wrong length or a sketch more.
struct StartMove {
  std::string body;
  double distance = 0.0;  // of its centre of mass (m)
  double angle = 0.0;     // |Δφ| (rad)
};
inline constexpr double kStartMoveTolerance = 1e-4;
inline constexpr double kStartTurnTolerance = 1e-4;

// One joint's reaction at one position, in the global frame and in the joint's frame.
// Convention (docs/notation.md): forces and moments that the second body of the joint exerts on
// the first.

// One position of the sweep, with its own storage: what compute_driven fills (and the sweep's
// working points). The stored positions of a CycleResult are read as DrivenPointView.
struct DrivenPoint {
  double input = 0.0, time = 0.0;
  double input_rate = 0.0, input_acceleration = 0.0;  // ṡ, s̈ of the driver's law at `time`
  VecX tangent;        // dq/ds = F / (dᵀF): the branch's direction per unit input
  double drive = 0.0;  // τ: drive torque (N·m) or force (N), from the driver onto the joint
  // With joint friction (analysis/friction.hpp): the drive without it, and the fixed-point
  // iterations the friction loads took (−1: not converged); τ and 0 without friction.
  double drive_frictionless = 0.0;
  int friction_iterations = 0;
  double chart_quality = 0.0;  // conditioning of the chart's block (→ 0 next to a change point)
  int chart_sign = 1;          // sign of det of the chart's block
  long chart_id = 0;           // the chart (count of switches so far)
  double dTF = 0.0;            // dᵀF, normalised: |dᵀF| / (|d| |F|) → 0 at a dead point
  VecX q, u, udot, lambda;     // λ: minimum-norm multipliers (rows of Eᵀ)
  std::vector<double> reactions;  // per ReactionComponent
  std::vector<double> measures;   // per Model::measures
  double kinetic = 0.0, potential = 0.0, dissipated = 0.0;
  // The generalised force that holds the idle degrees of freedom at zero rate (0 without idle
  // ones): its work per unit rate of each idle motion (unit angular rate: N·m, a torque about the
  // motion's axis; a translation: N), the largest in magnitude. Not a joint reaction; 0 (up to
  // rounding) when the motion is idle dynamically too.
  double idle_hold = 0.0;
  // At a change point (E loses rank; chart quality < 1e-4): the direct evaluation there is not
  // meaningful (the multipliers grow without bound as the rank drops). A grid position exactly
  // on one is first evaluated just past it.
  bool singular = false;
  // Next to a change point (chart quality < kBridgeQuality): index into CycleResult::bridges when
  // every value of this position (q, u, u̇, drive, reactions, measures, energies) was taken from
  // the branch — interpolated across the change point from positions on both sides where the
  // direct evaluation is well conditioned — instead of the ill-conditioned solve at q; −1 else.
  int bridge = -1;
};

// A stored position of CycleResult::points, read-only: the same fields as DrivenPoint, the vectors
// as Eigen maps and spans into the result's storage (valid while the CycleResult lives and is not
// changed).
struct DrivenPointView {
  double input = 0.0, time = 0.0;
  double input_rate = 0.0, input_acceleration = 0.0;
  Eigen::Map<const VecX> tangent;
  double drive = 0.0;
  double drive_frictionless = 0.0;
  int friction_iterations = 0;
  double chart_quality = 0.0;
  int chart_sign = 1;
  long chart_id = 0;
  double dTF = 0.0;
  Eigen::Map<const VecX> q, u, udot, lambda;
  std::span<const double> reactions;
  std::span<const double> measures;
  double kinetic = 0.0, potential = 0.0, dissipated = 0.0;
  double idle_hold = 0.0;
  bool singular = false;
  int bridge = -1;
};

// The positions of a sweep, stored compactly: the scalars of each position in one array and all
// its vectors (q, u, u̇, λ, tangent, reactions, measures) side by side in one contiguous block,
// reserved up front for the expected number of positions, instead of seven small heap blocks per
// position. Reads like a vector of positions: size(), operator[], front(), back(), range-for, each
// giving a DrivenPointView.
class DrivenPoints {
 public:
  [[nodiscard]] std::size_t size() const { return scalars_.size(); }
  [[nodiscard]] bool empty() const { return scalars_.empty(); }
  [[nodiscard]] DrivenPointView operator[](std::size_t k) const;
  [[nodiscard]] DrivenPointView front() const { return (*this)[0]; }
  [[nodiscard]] DrivenPointView back() const { return (*this)[size() - 1]; }
  // Room for `count` positions (the vectors' block once the first position gives their sizes).
  void reserve(std::size_t count);
  // Appends a copy of p. Every position of one sweep has the same vector sizes (else throws
  // std::logic_error).
  void push_back(const DrivenPoint& p);
  // Replaces position k by p (same vector sizes, else throws std::logic_error).
  void assign(std::size_t k, const DrivenPoint& p);
  // Measure i, an angle read modulo 2π, made continuous over the positions in order (each value
  // moved by whole turns to within π of the one before).
  void unwrap_measure(std::size_t i);

  class const_iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = DrivenPointView;
    using difference_type = std::ptrdiff_t;
    using pointer = void;
    using reference = DrivenPointView;
    const_iterator() = default;
    const_iterator(const DrivenPoints* points, std::size_t k) : points_(points), k_(k) {}
    DrivenPointView operator*() const { return (*points_)[k_]; }
    const_iterator& operator++() { return ++k_, *this; }
    const_iterator operator++(int) { return {points_, k_++}; }
    bool operator==(const const_iterator& o) const { return k_ == o.k_; }

   private:
    const DrivenPoints* points_ = nullptr;
    std::size_t k_ = 0;
  };
  [[nodiscard]] const_iterator begin() const { return {this, 0}; }
  [[nodiscard]] const_iterator end() const { return {this, size()}; }

 private:
  struct Scalars {
    double input, time, input_rate, input_acceleration, drive, drive_frictionless, chart_quality,
        dTF, kinetic, potential, dissipated, idle_hold;
    long chart_id;
    int chart_sign, friction_iterations;
    bool singular;
    int bridge;
  };
  [[nodiscard]] Scalars scalars_of(const DrivenPoint& p) const;
  void check_sizes(const DrivenPoint& p) const;
  void put_values(const DrivenPoint& p, double* v) const;
  std::vector<Scalars> scalars_;
  std::vector<double> values_;  // per position: tangent, q, u, udot, lambda, reactions, measures
  // Sizes of those vectors (fixed by the first position) and their sum, the stride of values_.
  Eigen::Index n_tangent_ = 0, n_q_ = 0, n_u_ = 0, n_lambda_ = 0;
  std::size_t n_reactions_ = 0, n_measures_ = 0, stride_ = 0;
};

struct DeadPoint {
  double input = 0.0;
  double time = 0.0;
  std::string message;
};

// Chart quality below which a position counts as next to a change point: there the direct
// evaluation loses accuracy like ε/quality³ (the computed q lies on a level set f = O(ε) of the
// constraints, whose curvature near the crossing of two branches is ε/δ³ at a distance δ), and
// its values are taken from the branch instead (CycleResult::bridges).
inline constexpr double kBridgeQuality = 0.05;

// A change point bridged on the branch: positions with time in (time_from, time_to) take their
// values from a polynomial through 8 positions on the branch at times t* ± {1, 2, 3, 4} ρ
// (ρ = time_to − t* = t* − time_from, where the chart quality is about kBridgeQuality, so that each
// of them is evaluated to full accuracy), degree 7 in time. Quantities that are smooth along the
// branch (q, velocities, accelerations, the drive, the measures and every bounded reaction
// component) are so their branch values — at the change point itself their limits from both
// sides. Components that grow without bound towards the change point (the minimum-norm
// multipliers along the self-stress that appears there) have no limit: they are marked
// `diverging` and not reported at the bridged positions.
struct ChangePointBridge {
  double input = 0.0, time = 0.0;  // the change point t* (as located by the sweep)
  double time_from = 0.0, time_to = 0.0;
  // Estimated error of the bridged drive (N·m or N): the largest difference between a node's
  // value and the degree-6 interpolant through the other seven, at the two inner nodes (an upper
  // estimate of the degree-7 interpolant's error). A bridge is used only when it is at most
  // kBridgeTolerance of the drive's size there.
  double drive_error = 0.0;
  std::vector<bool> diverging;  // per reaction component (CycleResult::components)
};
// A reaction component is `diverging` at a bridge when that estimate exceeds this fraction of
// its size at the nodes: a bounded component is interpolated to ~1e-10 of its size, one growing
// like 1/(t − t*) misses by O(1).
inline constexpr double kBridgeTolerance = 1e-6;

// invalid_request: the options do not fit the driver or the mechanism (a range for a harmonic
// law, a full turn of a prismatic joint, an empty range): a usage error, not a numerical one.
// stopped: a bound of CycleOptions::control was met (CycleResult::stop); the positions swept
// before it are kept.
enum class CycleStatus { completed, stopped_at_dead_point, failed, invalid_request, stopped };

struct CycleResult {
  CycleStatus status = CycleStatus::failed;
  StopReason stop = StopReason::none;  // which bound, when status is stopped
  std::string message;
  std::vector<ReactionComponent> components;
  std::vector<bool> determinate;       // per component: unique although constraints are redundant?
  std::vector<std::string> row_names;  // constraint rows
  std::vector<bool> row_determinate;   // per constraint row
  DrivenPoints points;
  std::vector<DeadPoint> dead_points;
  std::vector<DeadPoint> singular_positions;  // change points passed (rank drop of E)
  std::vector<ChangePointBridge> bridges;     // change points whose neighbourhood was bridged
  // Bodies the initial projection moved by more than the tolerances (StartMove), and a warning
  // per body, with lengths in mm and angles in degrees.
  std::vector<StartMove> start_moves;
  std::vector<std::string> warnings;
  // Per reaction component: grows without bound towards a change point (diverging at one of the
  // bridges): its peak over the cycle depends on how close the grid comes to the change point.
  std::vector<bool> diverging;
  long chart_switches = 0;
  // LU factorisations of the locked-input corrector's own Jacobian. Its steps are chord steps
  // with the chart's factorisation at the previous position while they converge fast (the usual
  // case: a few per sweep); this counts the fallbacks (next to change points, redundant rows).
  long corrector_factorisations = 0;
  int reversals = 0;  // dead points passed by reversing the input (reverse_at_dead_point)
  int rank = 0, dof = 0, redundant = 0;
  // Idle degrees of freedom (counted in dof), held at zero rate: dof − Σ count = 1 (the driver).
  std::vector<Mobility::Idle> idle;
  double idle_hold_peak = 0.0;  // max |DrivenPoint::idle_hold| over the positions
};

// Preallocated buffers of the driven computation (sizes fixed by the Model and the rank).
struct DrivenWorkspace {
  VecX d;       // n: Jacobian row of the input, ṡ = d u
  VecX Fdot_v;  // n: Ḟ v, from Eᵀ (Ḟ v) = −Dᵀ u
  VecX R;       // n: constraint reaction E λ, (C4)
  MatX N;       // nc × k: null space of E (redundancy directions); k = nc − r
  MatX NtN;     // k × k
  Eigen::LLT<MatX> NtN_llt;
  VecX small;                   // k
  VecX rhs_r;                   // r
  std::vector<int> other_rows;  // the k redundant rows (complement of the chart's rows)
  // n × n: [E_Rᵀ; dᵀ], Jacobian of the locked-input position problem (with redundant rows the
  // normal matrix EEᵀ + ddᵀ of all rows instead), then its LU in place. Empty on a large model
  // (sparse_jacobian() true): J is then kept in compressed form and factorised by KLU
  // (SparseJacobian, cycle.cpp), so that no n × n matrix is formed (a dense LU at n = 6000 is
  // 1.4e11 flops). Eᵀ is then held on its pattern there too, and every step of compute_driven,
  // compute_multi_driven and the corrector reads it there: the Workspace's ws.constraints.Et is
  // neither read nor written (the cycle builds its Workspace without it,
  // WorkspaceStages::constraint_matrices).
  MatX J;
  Eigen::VectorXi J_piv;  // n: row interchanges of that LU
  struct SparseJacobian;
  std::unique_ptr<SparseJacobian> J_sparse;
  [[nodiscard]] bool sparse_jacobian() const { return J_sparse != nullptr; }
  VecX g;   // n: scratch (a row of Eᵀ, for the null space N)
  VecX dq;  // n: right-hand side, then Newton step, of the corrector
  // R(φ_b) of every body at the q of the last compute_driven; the corrector updates it with Eᵀ.
  BodyPoses rotations;
  // Idle degrees of freedom held at zero rate (empty: none): their bodies (Mobility::idle), and
  // at the q of the last compute_driven the idle rows I (k × n), the idle motions V (n × k), I F
  // (k × n_a), the held basis F z (n), İ u (k) and the holding forces μ (k). Not allocation-free.
  std::vector<int> idle_bodies;
  MatX idle_I, idle_V, idle_IF;
  VecX F_held, idle_Idot_u, idle_mu;
  double length_scale = 1.0;  // of the mechanism (m): the step of the İ u differences
  // Joint friction (analysis/friction.hpp; empty: none): the pins, M u̇ + Ṁu − Q̂ before the
  // friction loads, the friction loads Q_f and the previous iterate of λ.
  std::vector<FrictionPin> friction;
  VecX R_inertia, Q_friction, lambda_previous;
  DrivenWorkspace(const Model& model, int rank, std::vector<int> idle_bodies = {},
                  int sparse_jacobian_from = kSparseJacobianFrom);
  DrivenWorkspace(DrivenWorkspace&&) noexcept;
  DrivenWorkspace& operator=(DrivenWorkspace&&) noexcept;
  ~DrivenWorkspace();
};

// What a driven position reports at its state (q, u) with u̇ and λ: every joint's reaction
// (compute_reactions), every measure, the kinetic and potential energies and the dissipated
// power. `rotations`: R(φ_b) of every body at state.q.
struct DrivenOutputs {
  std::vector<double>& reactions;
  std::vector<double>& measures;
  double& kinetic;
  double& potential;
  double& dissipated;
};
void compute_driven_outputs(const Model& model, const State& state, const VecX& lambda,
                            const VecX& udot, const BodyPoses& rotations, DrivenOutputs out);

// A driver's input s(t), ṡ(t), s̈(t) (SI): constant speed s0 + ω t, harmonic initial + a sin(2π f
// t), polynomial Σ c_k t^k.
void driver_law(const Driver& driver, double s0, double t, double& s, double& sdot, double& sddot);

// One position of a sweep with m drivers (analysis/multi_drive.hpp), SI.
struct MultiDrivenPoint {
  double time = 0.0;
  VecX inputs, input_rates, input_accelerations;  // m: the driven joints' coordinates s(t)
  VecX drives;                                    // m: each driver's torque (N·m) or force (N)
  VecX q, u, udot, lambda;
  std::vector<double> reactions;  // as CycleResult::components
  std::vector<double> measures;   // as Model::measures
  double kinetic = 0.0, potential = 0.0, dissipated = 0.0;
  // Smallest singular value of D_s F over its largest (0 where the drivers cannot move the
  // mechanism: a singular position of the drivers).
  double conditioning = 0.0;
};

// (C1)–(C4) with m drivers: D_s (m × n, the rows of the driven joints' coordinates) replaces the
// input row d. With F the basis of admissible velocities (n × m), G = D_s F:
//   u = F G⁻¹ ṡ;   u̇ = F v̇ + w,  Eᵀ w = −Dᵀu,  G v̇ = s̈ − (Ḋ_s u) − D_s w;
//   Fᵀ(M u̇ + Ṁu − Q̂) = Gᵀ τ  (the drivers' forces);   E λ = M u̇ + Ṁu − Q̂ − D_sᵀ τ.
// state.q must be on f(q) = 0; F must have m columns (else false, with out.conditioning 0).
// Returns false where G is singular (conditioning < 1e-12). Allocates (m-sized matrices).
bool compute_multi_driven(const Model& model, const std::vector<int>& joints, const VecX& sdot,
                          const VecX& sddot, State& state, Workspace& ws, DrivenWorkspace& dws,
                          MultiDrivenPoint& out);

// Velocities, accelerations, drive and multipliers at a position q on f(q) = 0 where the input
// moves with rate sdot and acceleration sddot (C1)–(C4). Returns false at a dead point (dᵀF = 0).
// DrivenJacobian::current: ws.constraints.Et already holds Eᵀ(q) and dws.rotations R(φ_b) at q
// (the corrector's last evaluation); `current_with_gradient`: and dws.d the gradient of the
// driver's coordinate at q; `evaluate` computes them. out.input is the driver's coordinate at q
// as the joint reads it (a spatial joint's angle in (−π, π]). With dws.idle_bodies the idle
// motions are held at zero rate (dᵀF is then that of the held basis F z). Allocation-free after
// set-up (without idle bodies).
enum class DrivenJacobian { evaluate, current, current_with_gradient };
bool compute_driven(const Model& model, int driver_joint, double sdot, double sddot, State& state,
                    Workspace& ws, DrivenWorkspace& dws, DrivenPoint& out,
                    DrivenJacobian jacobian = DrivenJacobian::evaluate);

// The sweep. Never throws for numerical trouble: the status says what happened.
[[nodiscard]] CycleResult run_cycle(const Model& model, const CycleOptions& options);

// Whether a position's drive, or reaction component `component`, is reported (outputs,
// summaries): everywhere except at a change point that could not be bridged (singular and not
// bridged), and except a component diverging at the bridge the position belongs to.
[[nodiscard]] bool drive_reported(const DrivenPointView& p);
// The same for the position's velocities and accelerations (the bodies', and every measure of a
// velocity or an acceleration): u = F v and u̇ come from the chart that fails at a change point
// that could not be bridged, so they are not reported there (its position q is). Before, they
// were written, up to 1e15 m/s² on an N-four-bar of N = 60, and that value set the acceleration
// column's noise floor, which printed every other acceleration of the cycle as 0.
[[nodiscard]] bool rates_reported(const DrivenPointView& p);
[[nodiscard]] bool measure_reported(const Model& model, const DrivenPointView& p,
                                    std::size_t measure);
[[nodiscard]] bool component_reported(const CycleResult& result, const DrivenPointView& p,
                                      std::size_t component);

[[nodiscard]] const char* to_string(CycleStatus s);

// ---- Summary (peaks and RMS) -----------------------------------------------------------------
// The magnitude of one joint's force (|(Fx, Fy)| in the global frame), moment |M| or scalar
// reaction (gear λ), built from the global reaction components. Indeterminate when any of its
// components is (the value is then the minimum-norm choice, docs/design.md §3).
struct ReactionMagnitude {
  std::string name;  // "A.|F|", "slide.|M|", "gear.|lambda|"
  std::string unit;  // "N" or "N*m"
  int joint = -1;
  std::vector<int> components;  // indices into CycleResult::components
  bool determinate = true;
};
[[nodiscard]] std::vector<ReactionMagnitude> reaction_magnitudes(const CycleResult& result);
[[nodiscard]] double magnitude_at(const DrivenPointView& p, const ReactionMagnitude& m);
// Whether every component of m is reported at p (component_reported).
[[nodiscard]] bool magnitude_reported(const CycleResult& result, const DrivenPointView& p,
                                      const ReactionMagnitude& m);

// One extreme of a series: its value and the input and time where it occurs.
struct SeriesExtreme {
  double value = 0.0, input = 0.0, time = 0.0;
};
// Signed maximum and minimum, peak |x| (with the input and time where each occurs) and RMS over
// the positions of the sweep where the series is reported (drive_reported, magnitude_reported,
// component_reported): bridged positions next to a change point count with their branch values,
// so none is biased by positions left out. A tie keeps the first position in sweep order.
struct SeriesSummary {
  std::string name, unit;
  bool determinate = true;
  // Some component grows without bound towards a change point (CycleResult::diverging): the peak
  // is that of the positions outside the bridged gaps and grows as the grid approaches it.
  bool diverges = false;
  double peak = 0.0, peak_input = 0.0, peak_time = 0.0, rms = 0.0;
  SeriesExtreme max, min;  // signed (for a magnitude: max = peak)
  int samples = 0;
};
// The drive first, then every reaction magnitude in joint order.
[[nodiscard]] std::vector<SeriesSummary> summarize_cycle(
    const CycleResult& result, const std::vector<ReactionMagnitude>& magnitudes,
    const std::string& drive_unit);
// Every reaction component (CycleResult::components order), signed.
[[nodiscard]] std::vector<SeriesSummary> summarize_components(const CycleResult& result);
// A series given by its value at every position of the sweep, counted where reported[k]
// (analysis/shaking.hpp's shaking force and moment). Throws std::invalid_argument unless both
// have one entry per position.
[[nodiscard]] SeriesSummary summarize_values(const CycleResult& result, std::string name,
                                             std::string unit, const std::vector<double>& values,
                                             const std::vector<bool>& reported);

}  // namespace orthomech

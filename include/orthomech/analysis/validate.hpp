#pragma once
// Validation of design positions (docs/design.md §1 job 3, issue 4). For every design position of
// the file (input values, optionally a target point/angle with a tolerance):
//   - assembly (analysis/assembly.hpp) and how far the design pose had to move;
//   - the assembly modes at the inputs (multi-start mass-metric projections, clustered), which
//     mode the position is on (with a target: the mode that meets it best);
//   - target met; DOF, rank and redundant equations there;
//   - singularity measures: σ_min of the constraint Jacobian and the transmission index η of the
//     input-locked Jacobian (docs/theory.md "Validation"), and the distance in input to the
//     nearest dead or change point on the position's circuit (arclength continuation of the
//     circuit, extremes of the input refined with NLopt);
//   - every planar four-bar loop (ground + 3 bodies in a ring of revolutes): Grashof type and
//     transmission angle (planar mechanisms only: not applicable to a spatial one, see
//     ValidationReport::not_applicable);
//   - defects of the set: circuit (positions on different circuits), branch (a dead or change
//     point between consecutive positions on a circuit), order (the input not monotone in the
//     given order).
// Spatial mechanisms (dimension 3, docs/spatial.md): the same report, with positions moved through
// q ⊕ δu (quaternions, nq ≠ n), the inputs locked on the spatial joints' coordinates (wrapped
// angles), idle degrees of freedom (docs/spatial.md §4.1) reported as mobility does and held at
// zero rate (mass-orthogonal) in η, the circuit trace and the mode comparison, and assembly modes
// on the drawn branch of every joint axis (h_i·h_j > 0, f_i·f_j > 0 for twist rows). Spatial
// targets: a point at a world position, optionally the orientation of its body (the whole frame,
// or one body axis along a world direction; DesignTarget). Spatial transmission loops (RSSR,
// RSSP, ...): Sutherland & Roth's transmission index, find_spatial_transmission_loops.
// Results are data; nothing here throws for a numerical outcome.
#include <optional>
#include <string>
#include <vector>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/run_control.hpp"

namespace orthomech {

struct ValidateOptions {
  int starts = 24;    // multi-start projections per position (assembly modes)
  unsigned seed = 1;  // random starts are reproducible
  double min_transmission = 30.0 * 0.017453292519943295;  // rad: |90° − μ| ≤ 90° − this passes
  // Spatial transmission loops: the Sutherland–Roth index below this fails; none: the planar
  // bound's equivalent, sin(min_transmission) (a planar four-bar's index is sin μ).
  std::optional<double> min_transmission_index;
  double min_sigma = 1e-6;  // σ_min and η below this: singular (fails)
  double step = 0.05;       // trace step (scaled coordinates: rad, length / L)
  int max_trace_steps = 20000;
  // The run's bounds (orthomech/run_control.hpp), asked at every multi-start projection and
  // trace step: a time limit, an interrupt flag, a progress callback. A bound met ends the
  // checks there (ValidationReport::stop); the report then does not pass.
  RunControl control;
};

enum class GrashofType {
  crank_rocker,           // s + l < p + q, input (crank) shortest
  rocker_crank,           // output shortest
  double_crank,           // ground shortest (drag link)
  grashof_double_rocker,  // coupler shortest
  triple_rocker,          // s + l > p + q (non-Grashof)
  change_point,           // s + l = p + q (folds: a change point exists)
};
[[nodiscard]] const char* to_string(GrashofType t);

// A planar four-bar loop: frame —P0— crank —P1— coupler —P2— follower —P3— frame, the Pk pins
// (revolute joints). Found on the pin graph of the mechanism: its vertices are the pins (the
// revolute joints, those at one point of a body merged into one pin: three links on one pivot
// are one pin), its edges the links between two pins of one body (a ternary link gives three).
// Every cycle of four pins through four distinct links is a four-bar loop; the frame is the
// ground when the loop holds it (a grounded loop), else the loop's link nearest the ground in
// the joint graph (a floating loop, e.g. the knee of a Jansen leg). A loop basis of the joint
// graph has j − b + 1 loops (j revolute joints, b links with the ground; `loop_basis_size`);
// the four-bar loops are every 4-cycle, whether or not in one basis. Oriented so that the input
// joint, when it is at a frame pin, is at P0; else the frame pin with the lower joint index.
struct FourBarLoop {
  int joints[4] = {-1, -1, -1, -1};  // a revolute joint at each pin (for names)
  int bodies[3] = {-1, -1, -1};      // crank, coupler, follower
  int frame = kGround;
  PointRef at[3];  // P1 and P2 on the coupler, P3 on the follower (transmission angle)
  double ground = 0.0, crank = 0.0, coupler = 0.0,
         follower = 0.0;  // link lengths, m (frame: ground)
  GrashofType type = GrashofType::triple_rocker;
};
// Every four-bar loop of the mechanism (revolutes only).
[[nodiscard]] std::vector<FourBarLoop> find_four_bar_loops(const Model& model, int input_joint);
// j − b + 1: the number of independent loops of the joint graph (revolutes, prismatics and
// spatial joints as edges, the ground and every body as vertices; a connected graph).
[[nodiscard]] int loop_basis_size(const Model& model);
// Grashof type from the four lengths (s + l vs p + q, which link is shortest); `tol` relative.
[[nodiscard]] GrashofType classify_grashof(double ground, double crank, double coupler,
                                           double follower, double tol = 1e-9);
// Transmission angle μ ∈ [0, π] at q: angle at the coupler–follower pin P2 between the coupler
// (toward P1) and the follower (toward its frame pivot P3).
[[nodiscard]] double transmission_angle(const Model& model, const FourBarLoop& loop, const VecX& q);

// A slider-crank loop: ground —j[0] revolute— crank —j[1] revolute— rod —j[2] revolute— slider
// —j[3] prismatic— ground. Its pressure angle is the angle between the rod (the line of the force
// it carries, a two-force member) and the slide axis.
struct SliderCrankLoop {
  int joints[4] = {-1, -1, -1, -1};
  int bodies[3] = {-1, -1, -1};   // crank, rod, slider
  double crank = 0.0, rod = 0.0;  // link lengths, m
};
// Every slider-crank loop of the mechanism.
[[nodiscard]] std::vector<SliderCrankLoop> find_slider_crank_loops(const Model& model);
// Pressure angle ∈ [0, π/2] at q: the acute angle between the rod (crank pin → wrist pin) and the
// slide axis. For an offset slider-crank, sin α = |r sin θ − e| / l.
[[nodiscard]] double pressure_angle(const Model& model, const SliderCrankLoop& loop, const VecX& q);

// A spatial transmission loop (dimension 3): ground —g_in— input link —c_in— coupler —c_out—
// output link —g_out— ground, g_in and g_out revolute or prismatic joints to the ground, and
//   - a binary coupler (no other joint) with spherical or universal ends, at least one spherical
//     (RSSR, RSUR, RSSP, ...): with no load on it, it carries one force along the line of its
//     two joint points (a universal end passes a moment only about its cross normal, which the
//     spherical end's zero moment forbids);
//   - or a distance row between the two links (c_in = c_out, coupler −1: a massless S–S rod);
//   - or a binary coupler with revolute ends whose axes, and the revolute ground axes, are all
//     parallel, every prismatic axis perpendicular to them (a planar four-bar or slider-crank
//     built with spatial joints): the force along the coupler line in the plane of motion.
// Oriented so that g_in is the input joint when it is one of the two ground joints; else g_in is
// the one with the lower index. `type`: the joint letters (R, P, S, U; D a distance row).
struct SpatialTransmissionLoop {
  int joints[4] = {-1, -1, -1, -1};  // g_in, c_in, c_out, g_out
  int bodies[3] = {-1, -1, -1};      // input link, coupler (−1: a distance row), output link
  bool planar = false;               // revolute coupler ends, parallel axes
  bool prismatic_output = false;
  std::string type;  // e.g. "RSUR", "RSUP", "RDR", "RRRR"
};
// Every spatial transmission loop of the mechanism (empty for a planar one).
[[nodiscard]] std::vector<SpatialTransmissionLoop> find_spatial_transmission_loops(
    const Model& model, int input_joint);
// Sutherland & Roth's transmission index at q [Sutherland & Roth 1973] (docs/theory.md): the
// virtual coefficient of the transmission wrench (a unit force along the coupler line, through
// its output-end point p, direction s) and the output twist (unit rotation about the output's
// ground axis a through o, or unit translation along a prismatic a), over its largest value for
// any line through p:
//   revolute output  TI = |a·((p − o) × s)| / |a × (p − o)|,   prismatic output  TI = |a·s|,
// in [0, 1]; s is taken in the plane of motion for a planar loop. For a planar four-bar it is
// sin μ (μ the transmission angle); 0 at a dead point of the output. 0 when p is on the axis.
[[nodiscard]] double spatial_transmission_index(const Model& model,
                                                const SpatialTransmissionLoop& loop, const VecX& q);

struct SingularityMeasures {
  double sigma_min = 0.0;  // σ_r/σ_1 of the scaled Eᵀ, r the generic rank (→ 0 at change points)
  std::optional<double> eta;  // σ_n/σ_1 of the scaled input-locked Jacobian [Eᵀ; d] (→ 0 at
                              // dead points and change points); none if not square or more
};
// `idle_bodies`: bodies with an idle degree of freedom (Mobility::idle); their own motions are
// locked mass-orthogonally in η (rows vᵀM for every v in the null space of Eᵀ restricted to the
// body), so that η measures the inputs' hold on the rest of the mechanism.
[[nodiscard]] SingularityMeasures singularity_measures(const Model& model, const VecX& q,
                                                       const std::vector<int>& input_joints,
                                                       int generic_rank,
                                                       const std::vector<int>& idle_bodies = {});

struct FourBarReport {
  std::string joints;  // "A0-A-B-B0"
  GrashofType type;
  double transmission = 0.0;  // μ, rad
  bool ok = true;             // min(μ, π − μ) ≥ min_transmission
};
struct SliderCrankReport {
  std::string joints;     // "O-A-B-slide"
  double pressure = 0.0;  // α, rad
  bool ok = true;         // α ≤ π/2 − min_transmission
};

struct SpatialLoopReport {
  std::string joints;  // "A0-A-B-B0" (a distance row once: "A0-rod-B0")
  std::string type;    // SpatialTransmissionLoop::type
  double index = 0.0;  // Sutherland–Roth transmission index, [0, 1]
  bool ok = true;      // index ≥ the bound (ValidateOptions::min_transmission_index)
};

// A joint limit that keeps a position from closing: without the limits it assembles with the
// joint at `needed` (rad or m), outside [limits.x(), limits.y()].
struct LimitBlock {
  int joint = -1;
  double needed = 0.0;
  bool angular = false;  // an angle (rad), else a slide (m)
};

struct PositionReport {
  std::string name;
  AssemblyStatus assembly = AssemblyStatus::failed;
  std::string assembly_message;
  bool assembles = false;
  VecX q;
  double distance = 0.0;                     // mass-metric distance from the design pose, √kg·m
  double max_translation = 0.0;              // largest body move from the design pose, m
  std::optional<double> target_error;        // |P − target|, m
  std::optional<double> target_angle_error;  // |Δφ|, rad
  bool target_met = true;
  int dof = 0, rank = 0;
  std::vector<std::string> redundant;
  std::vector<Mobility::Idle> idle;  // idle degrees of freedom (counted in dof), as mobility
  int idle_dof = 0;                  // Σ idle count: the inputs must fix dof − idle_dof
  SingularityMeasures singular;
  std::optional<double> singular_distance;  // |Δ input| to the nearest dead/change point, SI
  std::string singular_kind;                // "dead point" / "change point"
  std::optional<double> singular_input;     // input value there
  std::vector<FourBarReport> four_bars;
  std::vector<SliderCrankReport> slider_cranks;
  std::vector<SpatialLoopReport> spatial_loops;  // spatial transmission loops
  int modes = 0;                                 // distinct assembly modes found at the inputs
  int mode = -1;               // 1-based index of this position's mode (modes sorted by signature)
  std::string mode_signature;  // e.g. "+" per four-bar loop, then the sign of det [Eᵀ; d]
  int circuit = -1;            // 1-based, −1 when not traced (DOF ≠ 1 or no single input)
  int branch = -1;             // 1-based within the circuit
  std::vector<LimitBlock> limit_blocks;  // when it does not assemble because of joint limits
  std::vector<std::string> failures;     // checks that failed, in words
  [[nodiscard]] bool pass() const { return failures.empty(); }
};

struct ValidationReport {
  std::string input;           // input joint name ("" when positions have no common single input)
  bool input_angular = false;  // the input is an angle (rad), else a slide (m)
  std::vector<PositionReport> positions;
  int generic_rank = 0;
  bool circuit_defect = false, branch_defect = false, order_defect = false;
  std::vector<std::string> defects;          // in words
  int circuits = 0;                          // circuits traced
  std::vector<std::string> singular_points;  // every dead/change point found, in words
  // Checks that do not apply to this mechanism, in words (a spatial mechanism: Grashof type,
  // four-bar transmission angle, slider-crank pressure angle, and the Sutherland–Roth index when
  // it has no spatial transmission loop); empty for a planar one.
  std::vector<std::string> not_applicable;
  // The smallest Sutherland–Roth index over the loops and the assembled positions, and where
  // (none without spatial transmission loops); the bound applied.
  std::optional<double> min_transmission_index;
  std::string min_transmission_index_at;  // position name
  double transmission_index_bound = 0.0;
  // A bound of ValidateOptions::control met (none: every check ran): the checks after it did
  // not run, so the report does not pass; stop_message says where.
  StopReason stop = StopReason::none;
  std::string stop_message;
  [[nodiscard]] bool pass() const;
};

// Which joint limits keep `options` from assembling: assembles again without the limits, on the
// assembly mode of the design pose q_guess (the locks reached from it by continuation), and
// returns the joints whose coordinate then lies outside them (empty when it does not assemble
// either, or every limit is kept).
[[nodiscard]] std::vector<LimitBlock> find_limit_blocks(const Model& model, const VecX& q_guess,
                                                        const AssemblyOptions& options);

[[nodiscard]] ValidationReport validate_design_positions(const Model& model,
                                                         const ValidateOptions& options = {});

}  // namespace orthomech

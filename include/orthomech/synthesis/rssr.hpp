#pragma once
// The spatial RSSR function generator (issue 50; docs/synthesis.md, "Spatial RSSR function
// generation", (L50)–(L59)): its closed-form position, its synthesis from input–output angle
// pairs for revolute axes the designer places, and the candidate as a spatial mechanism file.
//
// Geometry (SI). Each revolute axis k (input 1, output 2) has a point P_k, a unit direction u_k
// and a unit reference direction e_k ⟂ u_k from which its angle is measured, right-handed about
// u_k; its frame is E_k = [e_k, u_k × e_k, u_k] (columns, world). The input crank turns by φ about
// u1, the output crank by ψ about u2; the spherical centres are fixed in the cranks' frames:
//   A(φ) = P1 + E1 Rz(φ) a,   B(ψ) = P2 + E2 Rz(ψ) b,                                   (L50)
// a = (a_x, a_y, a_z), b = (b_x, b_y, b_z): radius and phase in the crank's plane, and the offset
// along the axis from P_k. The coupler closes the loop, |B(ψ) − A(φ)| = L (the coupler length).
// Every evaluation is allocation-free.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "orthomech/synthesis/four_bar.hpp"
#include "orthomech/synthesis/function_generation.hpp"

namespace orthomech::synthesis {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

struct RevoluteAxis {
  Vec3 point = Vec3::Zero();       // P_k, world
  Vec3 direction = Vec3::UnitZ();  // u_k (any length: normalised)
  std::optional<Vec3> reference;   // e_k, made ⟂ u_k; none: the spatial file's default rule
                                   // (the world axis least aligned with u_k, projected)
};

struct Rssr {
  RevoluteAxis input;     // R1: the crank turned by φ
  RevoluteAxis output;    // R2: the crank that reads ψ
  Vec3 a = Vec3::Zero();  // the spherical centre A in the input crank's frame (L50)
  Vec3 b = Vec3::Zero();  // the spherical centre B in the output crank's frame (L50)
  double coupler = 0.0;   // L = |AB|
  int branch = 1;         // σ = ±1 of (L53)
};

// The frame E_k = [e_k, u_k × e_k, u_k] of an axis (L50). Throws std::invalid_argument for a zero
// direction or a reference parallel to it.
[[nodiscard]] Mat3 axis_frame(const RevoluteAxis& axis);

struct RssrPosition {
  bool assembles = false;
  double closure_gap = 0.0;  // |S| − √(P² + Q²) when it does not assemble (> 0), else 0 (L53)
  double psi = 0.0;          // ψ on the branch (L53) (the nearest configuration if it does not)
  Vec3 A = Vec3::Zero();     // world
  Vec3 B = Vec3::Zero();     // world
};

// Closed-form position at input angle φ on an explicit branch σ = ±1 (L51)–(L53):
//   P cos ψ + Q sin ψ + S = 0,  ψ = atan2(Q, P) + σ acos(−S / √(P² + Q²)).
[[nodiscard]] RssrPosition calc_position(const Rssr& linkage, double phi, int branch);
// The same on the linkage's branch.
[[nodiscard]] RssrPosition calc_position(const Rssr& linkage, double phi);

// B(ψ) = P2 + E2 Rz(ψ) b of (L50): the output crank's spherical centre at output angle ψ.
[[nodiscard]] Vec3 output_pin(const Rssr& linkage, double psi);

// The Sutherland–Roth transmission index of a position (the one validate reports for a spatial
// loop): |d̂ · t̂|, d̂ along the coupler A→B and t̂ = û2 × (B − P2) normalised, the direction B
// moves in; 1 when the coupler pushes B along its path, 0 at a dead position. A planar
// four-bar's index is sin μ (μ its transmission angle). 0 when B lies on the output axis.
[[nodiscard]] double transmission_index(const Rssr& linkage, const RssrPosition& position);

// Whether the input crank turns fully: the linkage assembles at every quarter degree of φ.
[[nodiscard]] bool input_turns_fully(const Rssr& linkage);

// ---- synthesis --------------------------------------------------------------------------------

// The design coordinates of (L58), in the order of the convention for fewer than 7 pairs: with n
// pairs the last 7 − n of {a_x, b_x, L, b_y, a_y, a_z, b_z} — b_z first, then a_z, a_y, b_y —
// are held at the values of RssrSynthesisOptions::held_a / held_b, so that the unknowns number
// min(n, 7) and the law fixes them (L58).
struct RssrSynthesisOptions {
  unsigned long seed = 1;  // quasi-random multistart (reproducible)
  int starts = 48;         // multistart BOBYQA runs of the outer search (L56)
  int local_evaluations = 400;
  // The half-width of the outer search box of a's free coordinates (m); 0: 2·|P2 − P1|
  // (1 m if the axis points coincide).
  double search_radius = 0.0;
  Vec3 held_a = Vec3::Zero();  // the values of a's held coordinates (L58)
  Vec3 held_b = Vec3::Zero();  // the values of b's held coordinates (L58)
};

struct RssrSynthesisResult {
  SynthesisStatus status = SynthesisStatus::no_linkage;
  std::string message;
  Rssr linkage;                   // the axes as given, a, b, L and the branch found
  std::vector<std::string> held;  // the coordinates held by the convention (L58), e.g. "b_z"
  double max_output_error = 0.0;  // rad: max |ψ(φ_i) − ψ_i| by the closed form (L53)
  double rms_output_error = 0.0;  // rad
  int evaluations = 0;            // objective evaluations of the outer search
  int polish_iterations = 0;      // Levenberg–Marquardt iterations (L57), over its starts
};

// Synthesis of an RSSR generating the pairs (φ_i, ψ_i) (3 to 1000) for the given axes (L54)–(L58):
// the outer search over a's free coordinates with (b, L) by linear least squares (L54)–(L55),
// then Levenberg–Marquardt on every free coordinate on the output-angle errors (L56)–(L57).
// Throws std::invalid_argument for fewer than 3 or more than 1000 pairs or a degenerate axis.
[[nodiscard]] RssrSynthesisResult synthesize_rssr(const RevoluteAxis& input,
                                                  const RevoluteAxis& output,
                                                  const std::vector<AnglePair>& pairs,
                                                  const RssrSynthesisOptions& options = {});

// ---- the mechanism file -----------------------------------------------------------------------

struct RssrFileOptions {
  std::string name = "rssr-candidate";
  std::string origin = "orthomech synthesis";  // where it came from (the comment block)
  std::string length_unit = "mm", angle_unit = "deg";
  double length_si = 1e-3, angle_si = 0.017453292519943295;
  double tolerance = 1e-6;           // m: a design position's target tolerance
  double mass_per_length = 1.0;      // kg/m
  double speed = 6.283185307179586;  // rad/s: the driver of the input
};

// The RSSR as a spatial mechanism file (docs/file-format.md, dimension 3; the layout of
// mechanisms/rssr.yaml): ground points A0 = P1, B0 = P2; bodies crank, coupler, rocker; joints
// A0 (revolute, axis u1, ref e1: its coordinate reads φ), A and B (spherical: the coupler's spin
// about AB is an idle degree of freedom, which validate reports and holds), B0 (revolute, axis
// u2, ref e2: reads ψ); the
// design pose at the first pair; one design position per pair: input A0 = φ_i, target the point
// rocker.B at B(ψ_i) (L50) within options.tolerance (L59). Throws std::invalid_argument for no
// pairs, a first pair that does not assemble, or a coupler along u2 there.
[[nodiscard]] std::string rssr_file(const Rssr& linkage, const std::vector<AnglePair>& pairs,
                                    const RssrFileOptions& options = {});

}  // namespace orthomech::synthesis

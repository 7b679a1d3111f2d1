#pragma once
// Planar four-bar and slider-crank descriptions with closed-form position analysis (issue 50,
// item 1): the independent oracle of the synthesis functions (function_generation.hpp,
// motion_generation.hpp, path_generation.hpp), which never solve the loop this way.
//
// Four-bar A0-A-B-B0 (docs/synthesis.md, "Four-bar position analysis", (L1)–(L6)):
//   ground pivots A0, B0 (world), crank a = |A0A|, coupler b = |AB|, follower c = |B0B|;
//   crank angle θ absolute (from the world x axis, counter-clockwise, radians);
//   coupler frame: origin A, x axis A→B; the coupler point P = A + R(β)·(p, q), β the coupler
//   angle; a frame attached to the coupler at P has the angle β + coupler_frame_angle.
//   branch +1: B to the left of the directed line A→B0, −1: to its right (for the crank-rocker of
//   mechanisms/crank-rocker.yaml at θ = 60° the +1 branch is its open assembly, B above A0B0).
// Every evaluation is allocation-free (Eigen fixed-size vectors only).
#include <Eigen/Core>
#include <array>

namespace orthomech::synthesis {

using Vec2 = Eigen::Vector2d;

struct FourBar {
  Vec2 A0 = Vec2::Zero();             // crank's ground pivot
  Vec2 B0 = Vec2(1.0, 0.0);           // follower's ground pivot
  double a = 0.0;                     // crank A0→A
  double b = 0.0;                     // coupler A→B
  double c = 0.0;                     // follower B0→B
  Vec2 coupler_point = Vec2::Zero();  // P = (p, q) in the coupler frame (origin A, x along A→B)
  double coupler_frame_angle = 0.0;   // angle of a frame carried at P relative to A→B
  int branch = 1;                     // +1 / −1 (see above)
};

// One position of a four-bar at crank angle θ. When `assembles` is false (|AB0| outside
// [|b − c|, b + c]) the points are those of the nearest (stretched/folded) configuration and
// `closure_gap` says by how much the loop fails to close (≥ 0; 0 when it assembles).
struct FourBarPosition {
  bool assembles = false;
  double closure_gap = 0.0;
  Vec2 A = Vec2::Zero();
  Vec2 B = Vec2::Zero();
  Vec2 P = Vec2::Zero();
  double coupler_angle = 0.0;       // β: angle of A→B from world x
  double follower_angle = 0.0;      // ψ: angle of B0→B from world x
  double transmission_angle = 0.0;  // μ ∈ [0, π]: angle at B between B→A and B→B0
  double frame_angle = 0.0;         // β + coupler_frame_angle: the angle of the frame at P
};

// Closed-form position at crank angle θ on the linkage's branch (circle intersection, (L1)–(L5)).
[[nodiscard]] FourBarPosition calc_position(const FourBar& linkage, double theta) noexcept;
// The same on an explicit branch (+1 / −1), ignoring linkage.branch.
[[nodiscard]] FourBarPosition calc_position(const FourBar& linkage, double theta,
                                            int branch) noexcept;

// Ground length d = |A0B0| and ground angle (of A0→B0 from world x).
[[nodiscard]] double ground_length(const FourBar& linkage) noexcept;
[[nodiscard]] double ground_angle(const FourBar& linkage) noexcept;

enum class GrashofType {
  crank_rocker,           // s + l < p + q, shortest = crank: the crank turns fully
  double_crank,           // s + l < p + q, shortest = ground (drag link)
  rocker_crank,           // s + l < p + q, shortest = follower: the follower turns, the crank rocks
  grashof_double_rocker,  // s + l < p + q, shortest = coupler: the coupler turns fully
  triple_rocker,          // s + l > p + q (non-Grashof): no link turns fully
  change_point,           // s + l = p + q (within tolerance): the linkage can fold flat
};
[[nodiscard]] const char* to_string(GrashofType type) noexcept;

// Grashof classification ((L6): s + l vs p + q, the shortest link's place). `relative_tolerance`
// is the band |s + l − p − q| ≤ tol·(s + l) read as a change point.
[[nodiscard]] GrashofType classify_grashof(const FourBar& linkage,
                                           double relative_tolerance = 1e-12) noexcept;

// The crank angles where the linkage assembles ((L7)): |θ − θ_g| ∈ [lower, upper] with θ_g the
// ground angle, symmetric about the ground line. full_turn: lower = 0 and upper = π. Otherwise up
// to two intervals of absolute crank angle, each [start, end] with end ≥ start (end − start < 2π),
// counter-clockwise; `count` 0 when the linkage assembles nowhere.
struct CrankRange {
  bool full_turn = false;
  double lower = 0.0;  // of |θ − θ_g|
  double upper = 0.0;
  int count = 0;
  std::array<std::array<double, 2>, 2> intervals{};
};
[[nodiscard]] CrankRange calc_crank_range(const FourBar& linkage) noexcept;

// The outcome of every synthesis function (function_generation.hpp, motion_generation.hpp,
// path_generation.hpp): data, never an exception.
enum class SynthesisStatus {
  ok,             // a linkage was found and reproduces the data within the stated residual
  no_linkage,     // the data give no real linkage (b² ≤ 0, a or c infinite, singular system)
  branch_defect,  // the precision points lie on different assembly branches
  not_converged,  // an iterative search stopped without meeting its tolerance (best so far)
};
[[nodiscard]] const char* to_string(SynthesisStatus status) noexcept;

// ---- slider-crank ---------------------------------------------------------------------------
// Crank pivot O, crank r = |OA|, coupler l = |AB|, slider B on the line through O + e·n with
// direction t = (cos γ, sin γ), n = (−sin γ, cos γ) (e the offset); slider position s along t
// from the foot O + e·n. branch +1: B ahead of A along t, −1 behind. Coupler point as FourBar.
struct SliderCrank {
  Vec2 O = Vec2::Zero();
  double r = 0.0;
  double l = 0.0;
  double offset = 0.0;                // e
  double line_angle = 0.0;            // γ
  Vec2 coupler_point = Vec2::Zero();  // in the frame origin A, x along A→B
  int branch = 1;
};

struct SliderCrankPosition {
  bool assembles = false;
  double closure_gap = 0.0;
  Vec2 A = Vec2::Zero();
  Vec2 B = Vec2::Zero();
  Vec2 P = Vec2::Zero();
  double s = 0.0;              // slider position along the line
  double coupler_angle = 0.0;  // angle of A→B from world x
};

// Closed form ((L8)): s = u + branch·√(l² − (e − v)²) with (u, v) = A − O in the line frame.
[[nodiscard]] SliderCrankPosition calc_position(const SliderCrank& linkage, double theta) noexcept;

}  // namespace orthomech::synthesis

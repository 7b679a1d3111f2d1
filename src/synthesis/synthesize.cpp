#include "orthomech/synthesis/synthesize.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "candidate_cycle.hpp"
#include "orthomech/analysis/validate.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/synthesis/function_generation.hpp"
#include "orthomech/synthesis/motion_generation.hpp"
#include "orthomech/synthesis/path_generation.hpp"
#include "orthomech/synthesis/slider_crank.hpp"

namespace orthomech::synthesis {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDegree = kPi / 180.0;

// A generator's four-bar (or slider-crank) before it is checked.
struct Raw {
  Linkage linkage;
  std::vector<double> crank_angles;
  std::string method;
  double output_offset = 0.0;  // function: the follower's angle is ψ + this
};

// ---- 1. The generators -------------------------------------------------------------------------

// 2–4 poses: what was given of a dyad, for the method's name ("crank's fixed pivot given").
std::string given_text(const char* role, const TaskPivots& p, size_t poses) {
  const std::string r = role;
  if (poses == 2) return r + "'s moving pivot given, fixed pivot on the bisector";
  if (p.fixed_pivot) return r + "'s fixed pivot given";
  if (p.moving_pivot) return r + "'s moving pivot given";
  return r + " from the centre-point curve";
}

// 2–4 poses with the task's given pivots (synthesize_motion_few_poses, (L26)–(L32)).
std::vector<Raw> few_pose_candidates(const SynthesisTask& task, const std::vector<Pose>& poses,
                                     SynthesisResult& result) {
  FewPoseOptions o;
  o.pivot_tolerance = result.tolerance;
  o.require_crank_rocker = task.crank_rocker;
  o.unit = task.length_si;
  o.unit_name = task.length_unit;
  const auto given = [](const TaskPivots& p) { return GivenPivots{p.fixed_pivot, p.moving_pivot}; };
  const MotionSynthesisResult m =
      synthesize_motion_few_poses(poses, given(task.crank), given(task.follower), o);
  result.status = m.status;
  result.message = m.message;
  const std::string method = std::to_string(poses.size()) + " poses, " +
                             given_text("crank", task.crank, poses.size()) + ", " +
                             given_text("follower", task.follower, poses.size());
  std::vector<Raw> raw;
  for (size_t k = 0; k < m.candidates.size(); ++k)
    raw.push_back({m.candidates[k].linkage, m.candidates[k].crank_angles,
                   m.candidates.size() == 1 ? method
                                            : method + " (pair " + std::to_string(k + 1) + " of " +
                                                  std::to_string(m.candidates.size()) + ")"});
  return raw;
}

std::vector<Raw> motion_candidates(const SynthesisTask& task, SynthesisResult& result) {
  std::vector<Pose> poses;
  for (size_t j = 0; j < task.positions.size(); ++j)
    poses.push_back({task.positions[j], task.angles[j]});
  if (poses.size() < 5) return few_pose_candidates(task, poses, result);
  MotionSynthesisOptions o;
  o.seed = task.seed;
  o.starts = std::max(8, task.starts / 2);
  const MotionSynthesisResult m = synthesize_motion_generator(poses, o);
  result.status = m.status;
  result.message = m.message;
  std::vector<Raw> raw;
  for (const MotionCandidate& c : m.candidates)
    raw.push_back({c.linkage, c.crank_angles,
                   (poses.size() == 5 ? "Burmester dyads " : "least-squares dyads ") +
                       std::to_string(c.crank_dyad + 1) + " (crank) and " +
                       std::to_string(c.follower_dyad + 1) + " (follower)"});
  return raw;
}

// The path options of a task, for one branch.
PathSynthesisOptions path_options(const SynthesisTask& task, const SynthesisRunOptions& run,
                                  int branch) {
  PathSynthesisOptions o;
  o.timing = task.timing == TaskTiming::prescribed   ? PathTiming::prescribed
             : task.timing == TaskTiming::free_start ? PathTiming::prescribed_free_start
                                                     : PathTiming::free;
  o.crank_angles = task.inputs;
  o.fixed_A0 = task.fixed_pivot;
  o.fixed_ground_angle = task.ground_angle;
  o.require_crank_rocker = task.crank_rocker;
  o.branch = branch;
  o.starts = task.starts;
  o.seed = task.seed;
  o.threads = run.threads;
  o.share = run.share;
  return o;
}

// A slider-crank's coupler path (slider_crank.hpp, (L46)–(L49)), one search per branch.
std::vector<Raw> slider_path_candidates(const SynthesisTask& task, const SynthesisRunOptions& run,
                                        SynthesisResult& result) {
  std::vector<Raw> raw;
  for (const int branch : {1, -1}) {
    const SliderPathResult p =
        synthesize_slider_path_generator(task.positions, path_options(task, run, branch));
    if (result.status != SynthesisStatus::ok) result.status = p.status, result.message = p.message;
    if (p.status == SynthesisStatus::no_linkage) continue;
    raw.push_back(
        {p.linkage, p.crank_angles,
         std::string("slider-crank path search on branch ") + (branch > 0 ? "+1" : "-1")});
  }
  return raw;
}

std::vector<Raw> path_candidates(const SynthesisTask& task, const SynthesisRunOptions& run,
                                 SynthesisResult& result) {
  if (task.linkage == TaskLinkage::slider_crank) return slider_path_candidates(task, run, result);
  std::vector<Raw> raw;
  for (const int branch : {1, -1}) {
    const PathSynthesisResult p =
        synthesize_path_generator(task.positions, path_options(task, run, branch));
    if (result.status != SynthesisStatus::ok) result.status = p.status, result.message = p.message;
    if (p.status == SynthesisStatus::no_linkage) continue;
    raw.push_back({p.linkage, p.crank_angles,
                   std::string("path search on branch ") + (branch > 0 ? "+1" : "-1")});
  }
  return raw;
}

// A slider-crank function generator (slider_crank.hpp, (L40)–(L45)): the outputs are the slider
// positions s_i.
std::vector<Raw> slider_function_candidates(const SynthesisTask& task, SynthesisResult& result) {
  std::vector<SliderPair> pairs;
  for (size_t i = 0; i < task.inputs.size(); ++i)
    pairs.push_back({task.inputs[i], task.outputs[i]});
  const SliderFunctionResult f = synthesize_slider_function_generator(pairs);
  result.status = f.status;
  result.message = f.message;
  if (f.status == SynthesisStatus::no_linkage) return {};
  std::vector<double> crank;
  for (const double phi : task.inputs) crank.push_back(phi + f.input_offset);
  return {{f.linkage, crank,
           pairs.size() == 3 ? "slider-crank, 3 precision pairs" : "slider-crank, least squares"}};
}

// A spatial RSSR function generator for the task's axes (rssr.hpp, (L54)–(L58)): the input
// crank's angle is the joint coordinate φ itself.
std::vector<Raw> rssr_function_candidates(const SynthesisTask& task, SynthesisResult& result) {
  std::vector<AnglePair> pairs;
  for (size_t i = 0; i < task.inputs.size(); ++i)
    pairs.push_back({task.inputs[i], task.outputs[i]});
  RssrSynthesisOptions o;
  o.seed = task.seed;
  o.starts = std::max(8, task.starts / 4);
  o.held_a = task.held_a;
  o.held_b = task.held_b;
  const RssrSynthesisResult f = synthesize_rssr(task.input_axis, task.output_axis, pairs, o);
  result.status = f.status;
  result.message = f.message;
  if (f.status == SynthesisStatus::no_linkage) return {};
  std::string method = pairs.size() >= 7 ? "RSSR, least squares" : "RSSR, exact";
  if (!f.held.empty()) {
    method += " (held:";
    for (const std::string& h : f.held) method += " " + h;
    method += ")";
  }
  return {{f.linkage, task.inputs, method}};
}

std::vector<Raw> function_candidates(const SynthesisTask& task, SynthesisResult& result) {
  if (task.linkage == TaskLinkage::slider_crank) return slider_function_candidates(task, result);
  if (task.linkage == TaskLinkage::rssr) return rssr_function_candidates(task, result);
  std::vector<AnglePair> pairs;
  for (size_t i = 0; i < task.inputs.size(); ++i)
    pairs.push_back({task.inputs[i], task.outputs[i]});
  const FunctionSynthesisResult f = synthesize_function_generator(pairs, task.ground);
  result.status = f.status;
  result.message = f.message;
  if (f.status == SynthesisStatus::no_linkage) return {};
  std::vector<double> crank;
  for (const double phi : task.inputs) crank.push_back(phi + f.input_offset);
  return {{f.linkage, crank,
           pairs.size() == 3 ? "Freudenstein, 3 precision pairs" : "Freudenstein, least squares",
           f.output_offset}};
}

// ---- 2. Checks of the closed form -----------------------------------------------------------

// The crank angles unwrapped in the targets' order, turning the way that reaches them all in
// less than a turn (the smaller total); false when neither sense does (an order defect).
bool unwrap_in_order(std::vector<double>& angles) {
  if (angles.size() < 2) return true;
  double ccw = 0.0, cw = 0.0;
  std::vector<double> step(angles.size(), 0.0);
  for (size_t j = 1; j < angles.size(); ++j) {
    step[j] = std::fmod(std::fmod(angles[j] - angles[j - 1], 2 * kPi) + 2 * kPi, 2 * kPi);
    ccw += step[j];
    cw += step[j] > 0.0 ? 2 * kPi - step[j] : 0.0;
  }
  const bool forward = ccw <= cw;
  for (size_t j = 1; j < angles.size(); ++j)
    angles[j] = angles[j - 1] + (forward ? step[j] : (step[j] > 0.0 ? step[j] - 2 * kPi : 0.0));
  return std::min(ccw, cw) < 2 * kPi;
}

// The rejection of a worst transmission angle below the task's bound.
void check_transmission(const SynthesisTask& task, SynthesisCandidate& c) {
  if (c.worst_transmission < task.min_transmission) {
    char m[160];
    std::snprintf(m, sizeof m,
                  "its worst transmission angle over the motion, %.3g deg, is below %.3g deg",
                  c.worst_transmission / kDegree, task.min_transmission / kDegree);
    c.rejections.emplace_back(m);
  }
}

// The worst transmission angle over the motion from the first target to the last, every degree at
// least: `mu(θ)` is the angle at the driver's angle θ, none where the linkage does not assemble
// (a rejection: the `driver` cannot turn through); then the task's bound (check_transmission).
template <class Mu>
void sweep_transmission(const SynthesisTask& task, SynthesisCandidate& c, const char* driver,
                        const Mu& mu) {
  const double from = c.crank_angles.front(), to = c.crank_angles.back();
  const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(to - from) / kDegree)));
  c.worst_transmission = kPi / 2;
  for (int k = 0; k <= steps; ++k) {
    const std::optional<double> m = mu(from + (to - from) * k / steps);
    if (!m) {
      c.rejections.push_back(std::string("the ") + driver +
                             " cannot turn from the first target to the last: the linkage does "
                             "not assemble between them");
      break;
    }
    c.worst_transmission = std::min(c.worst_transmission, *m);
  }
  check_transmission(task, c);
}

// A slider-crank's distances to the targets by the closed form ((L8): the slider pin B from its
// target for a function task, the coupler point for a path task), and its worst transmission
// angle π/2 − α over the crank's motion from the first target to the last (every degree and at
// the targets), α the pressure angle: sin α = |e − v| / l, v the crank pin's distance from the
// line through O.
void check_slider_crank(const SynthesisTask& task, const SliderCrank& sc, SynthesisCandidate& c) {
  const Vec2 t(std::cos(sc.line_angle), std::sin(sc.line_angle)), n(-t.y(), t.x());
  for (size_t j = 0; j < c.crank_angles.size(); ++j) {
    const SliderCrankPosition p = calc_position(sc, c.crank_angles[j]);
    if (!p.assembles) {
      c.rejections.push_back("it does not assemble at target " + std::to_string(j + 1));
      continue;
    }
    const Vec2 target = task.kind == TaskKind::function
                            ? Vec2(sc.O + sc.offset * n + task.outputs[j] * t)
                            : task.positions[j];
    c.max_distance =
        std::max(c.max_distance, ((task.kind == TaskKind::function ? p.B : p.P) - target).norm());
  }
  sweep_transmission(task, c, "crank", [&](double theta) -> std::optional<double> {
    const SliderCrankPosition p = calc_position(sc, theta);
    if (!p.assembles) return std::nullopt;
    const double v = (p.A - sc.O).dot(n);
    return kPi / 2 - std::asin(std::min(1.0, std::abs(sc.offset - v) / sc.l));
  });
}

// Distances to the targets by the closed form (calc_position), and the worst transmission angle
// over the crank's motion from the first target to the last (every degree and at the targets).
void check_four_bar(const SynthesisTask& task, const FourBar& fb, SynthesisCandidate& c) {
  for (size_t j = 0; j < c.crank_angles.size(); ++j) {
    const FourBarPosition p = calc_position(fb, c.crank_angles[j]);
    if (!p.assembles) {
      c.rejections.push_back("it does not assemble at target " + std::to_string(j + 1));
      continue;
    }
    if (task.kind == TaskKind::function) {  // the output angle, and the pin B's distance
      const double psi = task.outputs[j];   // the follower's world angle (offset included)
      const Vec2 B = fb.B0 + fb.c * Vec2(std::cos(psi), std::sin(psi));
      c.max_distance = std::max(c.max_distance, (p.B - B).norm());
      c.max_angle_error =
          std::max(c.max_angle_error, std::abs(std::remainder(p.follower_angle - psi, 2 * kPi)));
      continue;
    }
    c.max_distance = std::max(c.max_distance, (p.P - task.positions[j]).norm());
    if (task.kind == TaskKind::motion)
      c.max_angle_error = std::max(
          c.max_angle_error, std::abs(std::remainder(p.frame_angle - task.angles[j], 2 * kPi)));
  }
  c.grashof = classify_grashof(fb);
  if (task.crank_rocker && c.grashof != GrashofType::crank_rocker)
    c.rejections.push_back(std::string("not a Grashof crank-rocker (") + to_string(c.grashof) +
                           "), which the task requires");
  sweep_transmission(task, c, "crank", [&](double theta) -> std::optional<double> {
    const FourBarPosition p = calc_position(fb, theta);
    if (!p.assembles) return std::nullopt;
    return std::min(p.transmission_angle, kPi - p.transmission_angle);
  });
}

// An RSSR's output angles and rocker pin B against the pairs by the closed form (L53), and its
// worst transmission angle asin(index) over the input's motion from the first pair to the last
// (every degree and at the pairs; rssr.hpp, transmission_index).
void check_rssr(const SynthesisTask& task, const Rssr& r, SynthesisCandidate& c) {
  for (size_t j = 0; j < c.crank_angles.size(); ++j) {
    const RssrPosition p = calc_position(r, c.crank_angles[j]);
    if (!p.assembles) {
      c.rejections.push_back("it does not assemble at target " + std::to_string(j + 1));
      continue;
    }
    c.max_angle_error =
        std::max(c.max_angle_error, std::abs(std::remainder(p.psi - task.outputs[j], 2 * kPi)));
    c.max_distance = std::max(c.max_distance, (p.B - output_pin(r, task.outputs[j])).norm());
  }
  sweep_transmission(task, c, "input", [&](double phi) -> std::optional<double> {
    const RssrPosition p = calc_position(r, phi);
    if (!p.assembles) return std::nullopt;
    return std::asin(std::min(1.0, transmission_index(r, p)));
  });
}

void check_closed_form(const SynthesisTask& task, SynthesisCandidate& c) {
  if (const auto* fb = std::get_if<FourBar>(&c.linkage))
    check_four_bar(task, *fb, c);
  else if (const auto* r = std::get_if<Rssr>(&c.linkage))
    check_rssr(task, *r, c);
  else
    check_slider_crank(task, std::get<SliderCrank>(c.linkage), c);
}

// ---- 3. The file, read back and validated -------------------------------------------------------

void check_by_validate(const SynthesisTask& task, SynthesisCandidate& c) {
  Model model;
  try {
    model = parse_mechanism(c.file_text, c.name + ".yaml");
  } catch (const InputError& e) {
    c.rejections.push_back(std::string("its mechanism file does not read back: ") + e.what());
    return;
  }
  ValidateOptions vo;
  vo.min_transmission = task.min_transmission;
  const ValidationReport report = validate_design_positions(model, vo);
  for (const PositionReport& p : report.positions)
    for (const std::string& f : p.failures)
      c.rejections.push_back("validate, " + p.name + ": " + f);
  for (const std::string& d : report.defects) c.rejections.push_back("validate: " + d);
}

// The automatic tolerance: 1e-3 of the targets' size (their largest distance from their centroid;
// the ground for a function task), at least 1e-9 m.
double automatic_tolerance(const SynthesisTask& task) {
  if (task.tolerance > 0.0) return task.tolerance;
  if (task.kind == TaskKind::function && task.linkage == TaskLinkage::slider_crank) {
    double size = 0.0;  // the slider positions' largest magnitude
    for (const double s : task.outputs) size = std::max(size, std::abs(s));
    return std::max(1e-9, 1e-3 * size);
  }
  if (task.kind == TaskKind::function && task.linkage == TaskLinkage::rssr)
    return std::max(1e-9, 1e-3 * (task.output_axis.point - task.input_axis.point).norm());
  if (task.kind == TaskKind::function) return std::max(1e-9, 1e-3 * task.ground);
  Vec2 centre = Vec2::Zero();
  for (const Vec2& p : task.positions) centre += p;
  centre /= static_cast<double>(task.positions.size());
  double size = 0.0;
  for (const Vec2& p : task.positions) size = std::max(size, (p - centre).norm());
  return std::max(1e-9, 1e-3 * size);
}

// Whether the crank turns fully: the candidate's cycle is then a full turn (step 4).
bool crank_turns_fully(const Linkage& linkage) {
  if (const auto* fb = std::get_if<FourBar>(&linkage)) return calc_crank_range(*fb).full_turn;
  if (const auto* r = std::get_if<Rssr>(&linkage)) return input_turns_fully(*r);
  return crank_turns_fully(std::get<SliderCrank>(linkage));
}

// Accepted candidates have their cycle (step 4), so the kinetostatic keys are there.
void rank(const SynthesisTask& task, std::vector<SynthesisCandidate>& list) {
  std::stable_sort(list.begin(), list.end(), [&](const auto& a, const auto& b) {
    if (task.rank_by == "error") return a.max_distance < b.max_distance;
    if (task.rank_by == "drive_torque") return a.cycle->peak_drive < b.cycle->peak_drive;
    if (task.rank_by == "pin_force") return a.cycle->peak_pin_force < b.cycle->peak_pin_force;
    return a.worst_transmission > b.worst_transmission;
  });
}

// ---- The mechanism file
// --------------------------------------------------------------------------

// A number for the file: every digit a double has.
std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", v == 0.0 ? 0.0 : v);
  return b;
}
std::string point(const Vec2& p, double L) {
  return "[" + num(p.x() / L) + ", " + num(p.y() / L) + "]";
}

// The file's first keys: version, name, description, units (the task's).
void preamble(std::ostringstream& out, const SynthesisTask& task, const std::string& name,
              const std::string& linkage_note) {
  out << "orthomech: 1\nname: " << name << "\ndescription: \"" << to_string(task.kind)
      << " generation" << linkage_note << " for " << task.name << "\"\n";
  out << "units: {length: " << task.length_unit << ", angle: " << task.angle_unit
      << ", mass: kg, time: s, force: N}\n";
}

// A body's `pose:` [x, y, angle] in the task's units.
std::string pose_text(const SynthesisTask& task, const Vec2& at, double angle) {
  return "[" + num(at.x() / task.length_si) + ", " + num(at.y() / task.length_si) + ", " +
         num(angle / task.angle_si) + "]";
}

// A uniform slender link of `length` (m) between its frame origin and (length, 0): mass, inertia
// about its centre m L²/12, in the file's units (kg, kg·unit²).
void link_body(std::ostringstream& out, const SynthesisTask& task, const std::string& name,
               double length, const std::string& pose, const std::string& points,
               const std::string& extra = "") {
  const double L = task.length_si, m = task.mass_per_length * length;
  out << "  - name: " << name << "\n    mass: " << num(m)
      << "\n    inertia: " << num(m * length * length / 12.0 / (L * L)) << "\n    com: ["
      << num(length / 2.0 / L) << ", 0]\n    pose: " << pose << "\n    points: " << points << "\n"
      << extra;
}

}  // namespace

std::string four_bar_file(const SynthesisTask& task, const FourBar& fb,
                          const std::vector<double>& crank_angles, double tolerance,
                          const std::string& name) {
  const double L = task.length_si, A = task.angle_si;
  const FourBarPosition p0 = calc_position(fb, crank_angles.front());
  std::ostringstream out;
  out << "# " << name << ".yaml — a four-bar synthesised by `orthomech synthesize` from "
      << task.file << " (" << to_string(task.kind) << " generation, " << crank_angles.size()
      << " targets).\n"
      << "# Frames: each link's x axis runs from its first joint to its second (crank A0->A,\n"
      << "#   coupler A->B, rocker B0->B); joint A0 measures the crank angle. Links are uniform\n"
      << "#   slender rods of the task's mass per length. Design pose: the first target.\n"
      << "# Design positions t1..tn: the targets, at the crank angles the synthesis found.\n";
  preamble(out, task, name, "");
  out << "ground:\n  points: {A0: " << point(fb.A0, L) << ", B0: " << point(fb.B0, L) << "}\n";
  out << "bodies:\n";
  const auto pose = [&](const Vec2& at, double angle) { return pose_text(task, at, angle); };
  link_body(out, task, "crank", fb.a, pose(fb.A0, crank_angles.front()),
            "{A0: [0, 0], A: [" + num(fb.a / L) + ", 0]}");
  const double frame = std::remainder(fb.coupler_frame_angle, 2 * kPi);
  link_body(out, task, "coupler", fb.b, pose(p0.A, p0.coupler_angle),
            "{A: [0, 0], B: [" + num(fb.b / L) + ", 0], P: " + point(fb.coupler_point, L) + "}",
            "    outline: [[0, 0], " + point(fb.coupler_point, L) + ", [" + num(fb.b / L) +
                ", 0], [0, 0]]\n");
  link_body(out, task, "rocker", fb.c, pose(fb.B0, p0.follower_angle),
            "{B0: [0, 0], B: [" + num(fb.c / L) + ", 0]}");
  out << "joints:\n"
      << "  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}\n"
      << "  - {name: A, type: revolute, connects: [crank.A, coupler.A]}\n"
      << "  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}\n"
      << "  - {name: B0, type: revolute, connects: [ground.B0, rocker.B0]}\n";
  out << "measures:\n"
      << "  - {name: crank_angle, type: joint, joint: A0}\n"
      << "  - {name: rocker_angle, type: joint, joint: B0}\n"
      << "  - {name: transmission, type: angle, bodies: [coupler, rocker]}\n"
      << "  - {name: P_x, type: point, point: coupler.P, component: x}\n"
      << "  - {name: P_y, type: point, point: coupler.P, component: y}\n";
  out << "drivers:\n  - {name: motor, joint: A0, speed: " << num(task.speed) << " rad/s}\n";
  out << "design_positions:\n";
  for (size_t j = 0; j < crank_angles.size(); ++j) {
    out << "  - name: t" << j + 1 << "\n    inputs: {A0: " << num(crank_angles[j] / A) << "}\n";
    if (task.kind == TaskKind::function) {  // the follower at its output angle: the pin B there
      const double psi = task.outputs[j];   // the follower's world angle (offset included)
      const Vec2 B = fb.B0 + fb.c * Vec2(std::cos(psi), std::sin(psi));
      out << "    target: {point: rocker.B, at: " << point(B, L)
          << ", tolerance: " << num(tolerance / L) << "}\n";
      continue;
    }
    out << "    target: {point: coupler.P, at: " << point(task.positions[j], L);
    if (task.kind == TaskKind::motion)
      out << ", angle: " << num(std::remainder(task.angles[j] - frame, 2 * kPi) / A);
    out << ", tolerance: " << num(tolerance / L) << "}\n";
  }
  out << "analysis: {driver: motor, steps: 360}\n";
  return out.str();
}

// A slider-crank as a mechanism file: ground points O (the crank pivot) and X = O + e n (the foot
// of O on the slider line), the crank O->A, the rod A->B carrying the coupler point P, the slider
// at B (its frame x along the line, angle γ) on the prismatic joint `slide` from ground.X along
// t = (cos γ, sin γ): the joint's coordinate is the slider position s.
std::string slider_crank_file(const SynthesisTask& task, const SliderCrank& sc,
                              const std::vector<double>& crank_angles, double tolerance,
                              const std::string& name) {
  const double L = task.length_si, A = task.angle_si;
  const Vec2 t(std::cos(sc.line_angle), std::sin(sc.line_angle)), n(-t.y(), t.x());
  const Vec2 X = sc.O + sc.offset * n;
  const SliderCrankPosition p0 = calc_position(sc, crank_angles.front());
  std::ostringstream out;
  out << "# " << name << ".yaml — a slider-crank synthesised by `orthomech synthesize` from "
      << task.file << " (" << to_string(task.kind) << " generation, " << crank_angles.size()
      << " targets).\n"
      << "# Frames: crank O->A, rod A->B (coupler point P on the rod), slider frame at the pin B\n"
      << "#   with x along the slider line; the prismatic joint `slide` [ground.X, slider.B] has\n"
      << "#   the slider position s as its coordinate (X: the foot of O on the line, offset e).\n"
      << "#   Crank and rod are uniform slender rods of the task's mass per length; the slider a\n"
      << "#   square block of side l/4 and the rod's mass. Design pose: the first target.\n"
      << "# Design positions t1..tn: the targets, at the crank angles the synthesis found.\n";
  preamble(out, task, name, " (slider-crank)");
  out << "ground:\n  points: {O: " << point(sc.O, L) << ", X: " << point(X, L) << "}\n";
  out << "bodies:\n";
  const auto pose = [&](const Vec2& at, double angle) { return pose_text(task, at, angle); };
  link_body(out, task, "crank", sc.r, pose(sc.O, crank_angles.front()),
            "{O: [0, 0], A: [" + num(sc.r / L) + ", 0]}");
  link_body(out, task, "rod", sc.l, pose(p0.A, p0.coupler_angle),
            "{A: [0, 0], B: [" + num(sc.l / L) + ", 0], P: " + point(sc.coupler_point, L) + "}",
            "    outline: [[0, 0], " + point(sc.coupler_point, L) + ", [" + num(sc.l / L) +
                ", 0], [0, 0]]\n");
  const double m = task.mass_per_length * sc.l, side = sc.l / 4.0;
  out << "  - name: slider\n    mass: " << num(m)
      << "\n    inertia: " << num(m * side * side / 6.0 / (L * L))
      << "\n    com: [0, 0]\n    pose: " << pose(p0.B, sc.line_angle)
      << "\n    points: {B: [0, 0]}\n";
  out << "joints:\n"
      << "  - {name: O, type: revolute, connects: [ground.O, crank.O]}\n"
      << "  - {name: A, type: revolute, connects: [crank.A, rod.A]}\n"
      << "  - {name: B, type: revolute, connects: [rod.B, slider.B]}\n"
      << "  - {name: slide, type: prismatic, connects: [ground.X, slider.B], axis: [" << num(t.x())
      << ", " << num(t.y()) << "]}\n";
  out << "measures:\n"
      << "  - {name: crank_angle, type: joint, joint: O}\n"
      << "  - {name: slider_s, type: joint, joint: slide}\n"
      << "  - {name: P_x, type: point, point: rod.P, component: x}\n"
      << "  - {name: P_y, type: point, point: rod.P, component: y}\n";
  out << "drivers:\n  - {name: motor, joint: O, speed: " << num(task.speed) << " rad/s}\n";
  out << "design_positions:\n";
  for (size_t j = 0; j < crank_angles.size(); ++j) {
    out << "  - name: t" << j + 1 << "\n    inputs: {O: " << num(crank_angles[j] / A) << "}\n";
    if (task.kind == TaskKind::function)  // the slider pin at its position s_j on the line
      out << "    target: {point: slider.B, at: " << point(X + task.outputs[j] * t, L);
    else
      out << "    target: {point: rod.P, at: " << point(task.positions[j], L);
    out << ", tolerance: " << num(tolerance / L) << "}\n";
  }
  out << "analysis: {driver: motor, steps: 360}\n";
  return out.str();
}

namespace {

std::string mechanism_file(const SynthesisTask& task, const Linkage& linkage,
                           const std::vector<double>& crank_angles, double tolerance,
                           const std::string& name) {
  if (const auto* fb = std::get_if<FourBar>(&linkage))
    return four_bar_file(task, *fb, crank_angles, tolerance, name);
  if (const auto* r = std::get_if<Rssr>(&linkage)) {
    std::vector<AnglePair> pairs;
    for (size_t i = 0; i < crank_angles.size(); ++i)
      pairs.push_back({crank_angles[i], task.outputs[i]});
    RssrFileOptions o;
    o.name = name;
    o.origin = "`orthomech synthesize` of " + task.file;
    o.length_unit = task.length_unit, o.angle_unit = task.angle_unit;
    o.length_si = task.length_si, o.angle_si = task.angle_si;
    o.tolerance = tolerance;
    o.mass_per_length = task.mass_per_length;
    o.speed = task.speed;
    return rssr_file(*r, pairs, o);
  }
  return slider_crank_file(task, std::get<SliderCrank>(linkage), crank_angles, tolerance, name);
}

}  // namespace

SynthesisResult run_synthesis(const SynthesisTask& task, const SynthesisRunOptions& run) {
  SynthesisResult result;
  result.kind = task.kind;
  result.tolerance = automatic_tolerance(task);
  // 1. The generator.
  std::vector<Raw> raw;
  switch (task.kind) {
    case TaskKind::motion:
      raw = motion_candidates(task, result);
      break;
    case TaskKind::path:
      raw = path_candidates(task, run, result);
      break;
    case TaskKind::function:
      raw = function_candidates(task, result);
      break;
  }
  if (raw.empty() && result.message.empty())
    result.message = std::string("the generator found no ") + to_string(task.linkage);
  // 2.–4. Every candidate checked, validated and run through `cycle`.
  std::vector<SynthesisCandidate> all;
  std::vector<SynthesisTask> tasks;  // per candidate: a function's outputs as follower angles
  for (const Raw& r : raw) {
    SynthesisTask t = task;
    for (double& psi : t.outputs) psi += r.output_offset;
    tasks.push_back(std::move(t));
  }
  for (size_t k = 0; k < raw.size(); ++k) {
    const SynthesisTask& own = tasks[k];
    SynthesisCandidate c;
    c.task = k;
    c.name = "candidate-" + std::to_string(k + 1);
    c.method = raw[k].method;
    c.linkage = raw[k].linkage;
    c.crank_angles = raw[k].crank_angles;
    c.output_offset = raw[k].output_offset;
    if (!unwrap_in_order(c.crank_angles))
      c.rejections.emplace_back(
          "order defect: the crank does not reach the targets in their order "
          "within one turn");
    check_closed_form(own, c);
    if (c.max_distance > result.tolerance)
      c.rejections.emplace_back("a target is missed by more than the tolerance");
    try {
      c.file_text = mechanism_file(own, c.linkage, c.crank_angles, result.tolerance, c.name);
    } catch (const std::invalid_argument& e) {  // an RSSR the file cannot pose (rssr_file)
      c.rejections.push_back(std::string("its mechanism file cannot be written: ") + e.what());
      all.push_back(std::move(c));
      continue;
    }
    check_by_validate(own, c);
    if (c.accepted()) detail::check_by_cycle(c, crank_turns_fully(c.linkage));
    all.push_back(std::move(c));
  }
  // 5. Accepted ranked, rejected listed; names in that order.
  for (SynthesisCandidate& c : all) (c.accepted() ? result.accepted : result.rejected).push_back(c);
  rank(task, result.accepted);
  for (size_t k = 0; k < result.accepted.size(); ++k) {
    SynthesisCandidate& c = result.accepted[k];
    c.name = "candidate-" + std::to_string(k + 1);
    c.file_text =
        mechanism_file(tasks[c.task], c.linkage, c.crank_angles, result.tolerance, c.name);
  }
  for (size_t k = 0; k < result.rejected.size(); ++k)
    result.rejected[k].name = "rejected-" + std::to_string(k + 1);
  return result;
}

}  // namespace orthomech::synthesis

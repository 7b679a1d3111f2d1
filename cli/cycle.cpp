// `orthomech cycle FILE`: a driven mechanism swept through one cycle of its input — drive
// torque/force and every joint's reaction at every position, peaks and RMS, dead points, chart
// switches, which reaction components are unique (docs/design.md §6, docs/cli.md). No math here:
// the sweep is run_cycle (analysis/cycle.hpp), the files are io/cycle_output.hpp.
#include "orthomech/analysis/cycle.hpp"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "cycle_drivers.hpp"
#include "orthomech/analysis/cycle_friction.hpp"
#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/analysis/shaking.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/cycle_output.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/json_stream.hpp"
#include "orthomech/io/render.hpp"
#include "orthomech/io/report.hpp"
#include "orthomech/io/units.hpp"
#include "run_bounds.hpp"

namespace orthomech::cli {

namespace {

struct CycleCliOptions {
  std::string file;
  std::vector<std::string> sets;  // --set PATH=VALUE
  std::string driver;             // joint (or driver) name
  std::string speed;
  std::string from, to;
  int steps = 0;  // 0: the file's analysis.steps
  bool json = false;
  bool positions = false;
  std::string out;
  bool quiet = false, verbose = false;
  bool reverse = false;
  std::string units = "file";
  double speed_fluctuation = 0.0;    // C_s for the flywheel inertia (0: not asked)
  std::vector<std::string> drivers;  // --drivers A,B,…: the several-driver sweep
  double t_end = 0.0;                // --t-end (several drivers)
  double time_limit = 0.0;           // --time-limit (s of wall clock; 0: none)
  std::vector<std::string> traces;   // --trace BODY.POINT
  std::string animate;               // --animate FILE.svg
  std::string report;                // --report FILE.html
  std::string view;                  // --view (spatial pictures; "" is iso)
  double duration = 4.0;             // s per loop of the animation
  std::string shaking_about;         // --shaking-about X,Y[,Z] (file's length unit; "": origin)
};

std::string fmt(double v, int precision = 4) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", precision, v);
  return buf;
}

const char* profile_name(Profile p) {
  switch (p) {
    case Profile::constant_speed:
      return "constant-speed";
    case Profile::harmonic:
      return "harmonic";
    case Profile::polynomial:
      return "polynomial";
  }
  return "?";
}

bool is_angular(const Model& model, int joint) {
  return joint_coordinate_kind(model.joints[static_cast<size_t>(joint)]) == CoordinateKind::angle;
}

// The driver of the sweep: the file's (analysis.driver, else the first), changed by --driver and
// --speed. Bad options are command-line errors (exit 2).
Driver resolve_driver(const Model& model, const CycleCliOptions& opt) {
  const Driver* base = nullptr;
  for (const Driver& d : model.drivers)
    if (d.name == model.analysis.driver) base = &d;
  if (!base && !model.drivers.empty()) base = &model.drivers.front();
  Driver driver;
  if (!opt.driver.empty()) {
    int joint = model.find_joint(opt.driver);
    for (const Driver& d : model.drivers)
      if (joint < 0 && d.name == opt.driver) joint = d.joint;  // a driver's name works too
    if (joint < 0) {
      std::string names;
      for (const Joint& j : model.joints) names += (names.empty() ? "" : ", ") + j.name;
      throw CLI::ValidationError("--driver", "joint '" + opt.driver + "' is not defined in " +
                                                 model.file + " (joints: " + names + ")");
    }
    const Joint& j = model.joints[static_cast<size_t>(joint)];
    if (joint_coordinate_kind(j) == CoordinateKind::none)
      throw CLI::ValidationError("--driver", "joint '" + j.name + "' is a " + j.type_name() +
                                                 " joint; a driver needs a joint with a "
                                                 "coordinate (revolute, prismatic, cylindrical, "
                                                 "screw)");
    const Driver* on_joint = nullptr;
    for (const Driver& d : model.drivers)
      if (d.joint == joint) on_joint = &d;
    if (on_joint) {
      driver = *on_joint;
    } else {
      if (opt.speed.empty())
        throw CLI::ValidationError("--driver", "joint '" + j.name +
                                                   "' has no driver in the file: give --speed "
                                                   "too (e.g. --speed 300rpm)");
      driver.name = "command line";
      driver.joint = joint;
    }
  } else if (base) {
    driver = *base;
  } else {
    throw CLI::ValidationError("cycle", model.file +
                                            " has no driver: add one to the file (drivers:) or "
                                            "give --driver JOINT --speed 300rpm");
  }
  if (!opt.speed.empty()) {
    try {
      const UnitSystem file_units = unit_system(model.units);
      const bool angular = is_angular(model, driver.joint);
      driver.speed =
          parse_speed(opt.speed, angular,
                      (angular ? file_units.angle_si : file_units.length_si) / file_units.time_si);
    } catch (const std::invalid_argument& e) {
      throw CLI::ValidationError("--speed", e.what());
    }
    if (driver.speed == 0.0) throw CLI::ValidationError("--speed", "the speed must not be zero");
    driver.profile = Profile::constant_speed;
  }
  return driver;
}

std::string speed_text(const Driver& d, bool angular, const UnitSystem& u) {
  if (d.profile == Profile::harmonic)
    return "harmonic, amplitude " + format_input(d.amplitude, angular, u) + " about " +
           format_input(d.initial, angular, u) + ", " +
           fmt(output_unit(Dimension::frequency, u).from_si(d.frequency)) + " " +
           output_unit(Dimension::frequency, u).name;
  if (d.profile == Profile::polynomial) return "polynomial";
  const OutputUnit v = output_unit(angular ? Dimension::angular_velocity : Dimension::velocity, u);
  return angular ? "constant speed " + fmt(d.speed * 60.0 / (2.0 * std::numbers::pi)) + " rpm (" +
                       fmt(v.from_si(d.speed)) + " " + v.name + ")"
                 : "constant speed " + fmt(v.from_si(d.speed)) + " " + v.name;
}

// Runs `program arg` in `dir` (fork/exec: no shell, so any path works), stdout discarded,
// stderr to `log`. Returns the exit status, 127 when the program cannot be run.
int run_in_directory(const std::filesystem::path& dir, const std::string& program,
                     const std::string& arg, const std::filesystem::path& log) {
  const std::string dir_s = dir.string(), log_s = log.string();
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return 127;
  if (pid == 0) {  // child: only async-signal-safe calls until exec
    if (chdir(dir_s.c_str()) != 0) _exit(127);
    const int null_fd = open("/dev/null", O_WRONLY);
    const int log_fd = open(log_s.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (null_fd >= 0) dup2(null_fd, STDOUT_FILENO);
    if (log_fd >= 0) dup2(log_fd, STDERR_FILENO);
    const int in_fd = open("/dev/null", O_RDONLY);
    if (in_fd >= 0) dup2(in_fd, STDIN_FILENO);
    execlp(program.c_str(), program.c_str(), arg.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return 127;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 126;
}

// Every position: input, time, measures, body poses and named points, velocities and
// accelerations of the bodies, drive, reactions and energies, in the output units; one position's
// object at a time (the --json document streams them: io/json_stream.hpp).
class PositionJson {
 public:
  PositionJson(const Model& model, const CycleResult& r, bool angular, const UnitSystem& u,
               const NoiseFloor& noise)
      : model_(model),
        r_(r),
        u_(u),
        noise_(noise),
        angular_(angular),
        input_u_(output_unit(angular ? Dimension::angle : Dimension::length, u)),
        time_u_(output_unit(Dimension::time, u)),
        drive_u_(output_unit(angular ? Dimension::moment : Dimension::force, u)),
        energy_u_(output_unit(Dimension::moment, u)),
        length_u_(output_unit(Dimension::length, u)),
        angle_u_(output_unit(Dimension::angle, u)),
        q_(model.nq),
        columns_(position_columns(model)) {
    for (const Measure& m : model.measures)
      measure_u_.push_back(output_unit(dimension_of(m.unit), u));
    for (const ReactionComponent& c : r.components)
      component_u_.push_back(output_unit(dimension_of(c.unit), u));
    // The poses' columns come first, then the named points' (position_columns).
    for (const Body& b : model.bodies) pose_columns_ += static_cast<size_t>(b.nq());
  }
  [[nodiscard]] nlohmann::json operator()(const DrivenPointView& p);

 private:
  void add_poses(const DrivenPointView& p, nlohmann::json& j);
  void add_rates(const DrivenPointView& p, nlohmann::json& j) const;
  // Rounding noise of a dimension as 0 (io/noise.hpp).
  [[nodiscard]] double out(const OutputUnit& unit, Dimension d, double v) const {
    return unit.from_si(noise_.clean(d, v));
  }
  const Model& model_;
  const CycleResult& r_;
  const UnitSystem& u_;
  const NoiseFloor& noise_;
  bool angular_;
  OutputUnit input_u_, time_u_, drive_u_, energy_u_, length_u_, angle_u_;
  std::vector<OutputUnit> measure_u_, component_u_;
  std::vector<double> pose_;
  VecX q_;
  std::vector<PositionColumn> columns_;
  size_t pose_columns_ = 0;
};

nlohmann::json PositionJson::operator()(const DrivenPointView& p) {
  nlohmann::json j;
  j["input"] = input_u_.from_si(p.input);
  j["time"] = time_u_.from_si(p.time);
  j["singular"] = p.singular;
  j["bridged"] = p.bridge >= 0;
  nlohmann::json m = nlohmann::json::object();
  for (size_t i = 0; i < model_.measures.size(); ++i)  // null: not reported (rates_reported)
    m[model_.measures[i].name] =
        measure_reported(model_, p, i)
            ? nlohmann::json(
                  out(measure_u_[i], dimension_of(model_.measures[i].unit), p.measures[i]))
            : nlohmann::json(nullptr);
  j["measures"] = m;
  add_poses(p, j);
  add_rates(p, j);
  if (drive_reported(p)) {  // not at a change point that could not be bridged
    j["drive"] = out(drive_u_, angular_ ? Dimension::moment : Dimension::force, p.drive);
    nlohmann::json rc = nlohmann::json::object();
    for (size_t i = 0; i < r_.components.size(); ++i)
      if (component_reported(r_, p, i))
        rc[r_.components[i].name] =
            out(component_u_[i], dimension_of(r_.components[i].unit), p.reactions[i]);
    j["reactions"] = rc;
  }
  nlohmann::json outside = nlohmann::json::array();
  for (size_t jt = 0; jt < model_.joints.size(); ++jt)
    if (outside_limits(model_, static_cast<int>(jt), q_)) outside.push_back(model_.joints[jt].name);
  j["outside_limits"] = outside;
  j["kinetic_energy"] = energy_u_.from_si(p.kinetic);
  j["potential_energy"] = energy_u_.from_si(p.potential);
  return j;
}

// Pose of every body's frame ([x, y, angle]; a particle [x, y]; a spatial body [x, y, z, e0, e1,
// e2, e3], its unit quaternion) and every named point ([x, y] or [x, y, z]), in position_columns
// order.
void PositionJson::add_poses(const DrivenPointView& p, nlohmann::json& j) {
  q_ = p.q;  // copied once per position (not once per joint: O(N²) on the N-four-bar)
  compute_output_positions(model_, q_, pose_);
  nlohmann::json poses = nlohmann::json::object(), points = nlohmann::json::object();
  for (size_t c = 0; c < columns_.size(); ++c) {
    const std::string& name = columns_[c].name;
    const std::string owner = name.substr(0, name.rfind('.'));
    const double v = columns_[c].dimension == Dimension::none
                         ? pose_[c]
                         : out(columns_[c].dimension == Dimension::angle ? angle_u_ : length_u_,
                               columns_[c].dimension, pose_[c]);
    (c < pose_columns_ ? poses : points)[owner].push_back(v);
  }
  j["poses"] = poses;
  j["named_points"] = points;
}

// Velocities and accelerations of every body's centre of mass (and angular ones); none at a
// change point that could not be bridged (rates_reported).
void PositionJson::add_rates(const DrivenPointView& p, nlohmann::json& j) const {
  nlohmann::json bodies = nlohmann::json::object();
  for (const Body& b : model_.bodies) {
    if (!rates_reported(p)) break;
    std::vector<double> v, a;
    for (int i = 0; i < b.nu(); ++i) {
      const VelocityComponent& c = velocity_component(b, i);
      v.push_back(
          out(output_unit(c.velocity_dimension, u_), c.velocity_dimension, p.u(b.u_offset + i)));
      a.push_back(out(output_unit(c.acceleration_dimension, u_), c.acceleration_dimension,
                      p.udot(b.u_offset + i)));
    }
    bodies[b.name] = {{"velocity", v}, {"acceleration", a}};
  }
  j["bodies"] = bodies;
}

// The positions of the sweep as vectors (SI): for the traces and the frames of the pictures.
struct SweepPositions {
  std::vector<VecX> q;
  std::vector<double> input;
};
SweepPositions sweep_positions_of(const CycleResult& r) {
  SweepPositions s;
  s.q.reserve(r.points.size());
  s.input.reserve(r.points.size());
  for (const DrivenPointView& p : r.points) {
    s.q.emplace_back(p.q);
    s.input.push_back(p.input);
  }
  return s;
}

// The traces' columns of cycle.csv: "trace coupler.P.x", "trace coupler.P.y" (spatial: and
// "trace coupler.P.z").
std::vector<ExtraColumn> trace_columns(const std::vector<PointTrace>& traces) {
  std::vector<ExtraColumn> cols;
  for (const PointTrace& t : traces) {
    ExtraColumn x{"trace " + t.point + ".x", Dimension::length, {}, {}, false};
    ExtraColumn y{"trace " + t.point + ".y", Dimension::length, {}, {}, false};
    for (const Vec2& p : t.path) {
      x.values.push_back(p.x());
      y.values.push_back(p.y());
    }
    cols.push_back(std::move(x));
    cols.push_back(std::move(y));
    if (!t.z.empty())
      cols.push_back(ExtraColumn{"trace " + t.point + ".z", Dimension::length, t.z, {}, false});
  }
  return cols;
}

// The report's plots (output units): the drive, the reaction force magnitudes and the reaction
// moment magnitudes versus the input, and the shaking force's components and magnitude; a value
// that is not reported is left out (null).
std::vector<ReportPlot> report_plots(const Model& model, const CycleResult& r,
                                     const std::vector<ReactionMagnitude>& magnitudes,
                                     const ShakingSeries& shaking, bool angular,
                                     const UnitSystem& u) {
  std::vector<ReportPlot> plots;
  const OutputUnit drive_u = output_unit(angular ? Dimension::moment : Dimension::force, u);
  ReportPlot drive{"drive", angular ? "drive torque" : "drive force", drive_u.name, {}};
  ReportSeries d{"drive", {}};
  for (const DrivenPointView& p : r.points)
    d.values.push_back(drive_reported(p) ? std::optional(drive_u.from_si(p.drive)) : std::nullopt);
  drive.series.push_back(std::move(d));
  plots.push_back(std::move(drive));
  ReportPlot forces{"forces", "reaction forces", output_unit(Dimension::force, u).name, {}};
  ReportPlot moments{"moments", "reaction moments", output_unit(Dimension::moment, u).name, {}};
  for (const ReactionMagnitude& m : magnitudes) {
    const Dimension dim = dimension_of(m.unit);
    const OutputUnit mu = output_unit(dim, u);
    ReportSeries s{m.name, {}};
    for (const DrivenPointView& p : r.points)
      s.values.push_back(magnitude_reported(r, p, m) ? std::optional(mu.from_si(magnitude_at(p, m)))
                                                     : std::nullopt);
    (dim == Dimension::force ? forces : moments).series.push_back(std::move(s));
  }
  if (!forces.series.empty()) plots.push_back(std::move(forces));
  if (!moments.series.empty()) plots.push_back(std::move(moments));
  const OutputUnit fu = output_unit(Dimension::force, u);
  ReportPlot shake{"shaking", "shaking force on the frame", fu.name, {}};
  const char* axes[3] = {"x", "y", "z"};
  for (int i = 0; i <= model.dimension; ++i) {  // x, y[, z], then |F_s|
    ReportSeries sr{i == model.dimension ? "|F_s|" : std::string("F_s ") + axes[i], {}};
    for (size_t k = 0; k < shaking.force.size(); ++k)
      sr.values.push_back(shaking.reported[k] ? std::optional(fu.from_si(
                                                    i == model.dimension ? shaking.force[k].norm()
                                                                         : shaking.force[k](i)))
                                              : std::nullopt);
    shake.series.push_back(std::move(sr));
  }
  plots.push_back(std::move(shake));
  return plots;
}

// What one `cycle` run shares among its steps once the sweep is done: the request, the result,
// its summaries and metrics, and the units of the outputs.
struct CycleRun {
  const CycleCliOptions& opt;
  const Model& model;
  const CycleOptions& co;
  const CycleResult& r;
  bool angular = false;
  UnitSystem U;
  std::string drive_unit_si{};  // "N*m" (revolute driver) or "N"
  std::vector<ReactionMagnitude> magnitudes{};
  std::vector<SeriesSummary> summary{};
  std::vector<SeriesSummary> component_summary{};
  CycleMetrics metrics{};
  ShakingSeries shaking{};
  std::vector<SeriesSummary> shaking_summary{};   // |F_s| and M_s (JSON peaks; summary_metrics)
  FrictionSeries friction{};                      // the pins' friction (empty: none)
  std::vector<SeriesSummary> friction_summary{};  // drive without friction, moments, power
  SweepPositions sweep{};
  std::vector<PointTrace> traces{};
  NoiseFloor noise{};
  // Units of the outputs.
  OutputUnit input_u{}, time_u{}, power_u{}, energy_u{}, inertia_u{}, angle_u{}, speed_u{},
      length_u{};
  [[nodiscard]] OutputUnit unit_of(const std::string& si) const {
    return output_unit(dimension_of(si), U);
  }
  // Angles at extremes in [0°, 360°) (the sweep line keeps the continuous input).
  [[nodiscard]] double wrapped(double s) const {
    if (!angular) return s;
    double w = std::fmod(s, 2.0 * std::numbers::pi);
    if (w < 0.0) w += 2.0 * std::numbers::pi;
    return w > 2.0 * std::numbers::pi - 1e-9 ? 0.0 : w;
  }

  // The units of the outputs from U (input and speed: the driver's angle or length).
  void set_output_units() {
    input_u = output_unit(angular ? Dimension::angle : Dimension::length, U);
    time_u = output_unit(Dimension::time, U);
    power_u = output_unit(Dimension::power, U);
    energy_u = output_unit(Dimension::moment, U);
    inertia_u = output_unit(Dimension::inertia, U);
    angle_u = output_unit(Dimension::angle, U);
    speed_u = output_unit(angular ? Dimension::angular_velocity : Dimension::velocity, U);
    length_u = output_unit(Dimension::length, U);
  }

  // The output steps (4 to 7 of run_cycle_command), on the members above.
  void log_cycle() const;
  [[nodiscard]] std::string write_files() const;
  [[nodiscard]] nlohmann::json json_document() const;  // without the positions
  void write_json(std::ostream& out) const;
  [[nodiscard]] std::string summary_text(const std::string& files_note) const;
  void write_pictures(const Projection& projection, const std::string& text) const;

 private:
  // Parts of the JSON document.
  [[nodiscard]] nlohmann::json extreme_json(const SeriesExtreme& e, const OutputUnit& u) const;
  [[nodiscard]] nlohmann::json events_json(const std::vector<DeadPoint>& v) const;
  void add_run_json(nlohmann::json& j) const;
  [[nodiscard]] nlohmann::json bridges_json() const;
  [[nodiscard]] nlohmann::json peaks_json() const;
  [[nodiscard]] nlohmann::json components_json() const;
  [[nodiscard]] nlohmann::json loops_json() const;
  void add_power_json(nlohmann::json& j) const;
  void add_friction_json(nlohmann::json& j) const;
  [[nodiscard]] nlohmann::json strokes_json() const;
  [[nodiscard]] nlohmann::json limits_json() const;
  [[nodiscard]] nlohmann::json traces_json() const;
  // Parts of the terminal summary.
  void summary_run(std::ostream& out) const;
  void summary_events(std::ostream& out) const;
  void summary_table(std::ostream& out) const;
  void summary_metrics(std::ostream& out) const;
  void summary_traces(std::ostream& out) const;
  void summary_shaking(std::ostream& out) const;
  void summary_friction(std::ostream& out) const;
  void summary_friction_bound(std::ostream& out) const;
  void summary_indeterminate(std::ostream& out) const;
};

// Step 1: the sweep's request from the options: driver, steps, reversal and the input range
// (bare numbers in the file's declared units: an angle in deg in a deg file).
CycleOptions cycle_request(const Model& model, const CycleCliOptions& opt, const UnitSystem& U) {
  const UnitSystem file_units = unit_system(model.units);
  CycleOptions co;
  co.driver = resolve_driver(model, opt);
  const bool angular = is_angular(model, co.driver.joint);
  co.steps = opt.steps > 0 ? opt.steps : model.analysis.steps;
  co.reverse_at_dead_point = opt.reverse;
  // Bare numbers are in the file's declared units (an angle in deg in a deg file).
  const double bare = angular ? file_units.angle_si : file_units.length_si;
  try {
    if (!opt.from.empty()) {
      co.use_start = true;
      co.start = parse_position(opt.from, angular, bare);
    }
    if (!opt.to.empty()) {
      co.full_cycle = false;
      co.end = parse_position(opt.to, angular, bare);
    }
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError(opt.from.empty() ? "--to" : "--from/--to", e.what());
  }
  if (!opt.from.empty() && opt.to.empty() && !angular)
    throw CLI::ValidationError("--to", "a prismatic driver needs the end of the range (--to)");
  if (!opt.from.empty())
    spdlog::info("start input {} ({})", format_input(co.start, angular, U), opt.from);
  if (!opt.to.empty()) spdlog::info("end input {} ({})", format_input(co.end, angular, U), opt.to);
  return co;
}

// Step 3: the sweep's outcome: a request the sweep rejected is an input error (the file's, at
// the driver's line, when the driver is the file's as written); a sweep without any position is
// a numerical failure (kNumerical); else std::nullopt, the run goes on.
std::optional<int> check_cycle_outcome(const Model& model, const CycleCliOptions& opt,
                                       const CycleOptions& co, const CycleResult& r) {
  if (r.status == CycleStatus::invalid_request) {
    // A driver taken from the file as written: the problem is the file's, at the driver's line.
    if (opt.speed.empty() && opt.from.empty() && opt.to.empty() && co.driver.where.line > 0)
      throw InputError(co.driver.where, "driver '" + co.driver.name + "'", r.message);
    throw CLI::ValidationError(model.file, r.message);
  }
  if (r.status == CycleStatus::failed && r.points.empty()) {
    spdlog::error("{}: the cycle cannot be computed: {}", model.file, r.message);
    return kNumerical;
  }
  return std::nullopt;
}

// Step 4: the log (stderr): a stopped sweep, warnings, idle degrees of freedom, dead and
// singular points, chart switches.
void CycleRun::log_cycle() const {
  if (r.status == CycleStatus::failed)
    spdlog::error("{}: the sweep stopped: {}", model.file, r.message);
  for (const std::string& w : r.warnings) spdlog::warn("{}: {}", model.file, w);
  if (!r.idle.empty()) {  // idle degrees of freedom (counted in the DOF), held at zero rate
    std::string bodies;
    for (const Mobility::Idle& i : r.idle) {
      bodies.append(bodies.empty() ? "body '" : "; body '").append(i.body).append("' (");
      bodies.append(std::to_string(i.count)).append(i.count == 1 ? " direction)" : " directions)");
    }
    spdlog::info(
        "{}: idle degrees of freedom held at zero rate (mass-orthogonal to the driven motion, "
        "not dead points): {}",
        model.file, bodies);
  }
  if (r.status == CycleStatus::stopped_at_dead_point) spdlog::warn("{}: {}", model.file, r.message);
  if (r.status == CycleStatus::stopped) spdlog::error("cycle: stopped: {}", r.message);
  for (const DeadPoint& d : r.singular_positions) spdlog::info("{}", d.message);
  spdlog::info(
      "{} chart switches: the dual form changed its independent velocities {} times along the "
      "sweep (bookkeeping of the method; the results do not depend on it)",
      model.file, r.chart_switches);
  if (opt.speed_fluctuation > 0.0 && !metrics.power.flywheel_inertia)
    spdlog::warn(
        "--speed-fluctuation: no flywheel inertia (it needs a revolute driver and a drive)");
}

// Step 5: the files of --out (cycle.csv, cycle.gp and gnuplot's plots), before anything goes to
// stdout so that a failure to write is reported first. Returns the note of the files written
// ("" without --out).
std::string CycleRun::write_files() const {
  std::string files_note;
  if (!opt.out.empty()) {
    const std::filesystem::path dir(opt.out);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw CLI::ValidationError("--out", "cannot create " + opt.out + ": " + ec.message());
    try {
      std::vector<ExtraColumn> extra = trace_columns(traces);
      for (ExtraColumn& col : friction_columns(model, r, friction, angular))
        extra.push_back(std::move(col));
      for (ExtraColumn& col : shaking_columns(model, shaking)) extra.push_back(std::move(col));
      const CycleColumns cols =
          write_cycle_csv(dir / "cycle.csv", model, r, magnitudes, angular, U, extra);
      write_cycle_gnuplot(dir / "cycle.gp", "cycle.csv", model, r, magnitudes, cols, angular, U,
                          speed_text(co.driver, angular, U));
    } catch (const std::runtime_error& e) {
      throw CLI::ValidationError("--out", e.what());
    }
    // gnuplot: ORTHOMECH_GNUPLOT names the program ("none" disables it); default "gnuplot".
    const char* env = std::getenv("ORTHOMECH_GNUPLOT");
    const std::string gnuplot = env && *env ? env : "gnuplot";
    bool plotted = false;
    if (gnuplot == "none") {
      spdlog::warn("plots skipped (ORTHOMECH_GNUPLOT=none): wrote {}/cycle.csv and {}/cycle.gp",
                   opt.out, opt.out);
    } else {
      const int status = run_in_directory(dir, gnuplot, "cycle.gp", dir / "gnuplot.log");
      plotted = status == 0;
      if (status == 127) {
        spdlog::warn(
            "gnuplot not found: wrote {}/cycle.csv and {}/cycle.gp; for the plots install "
            "gnuplot-nox (apt-get install gnuplot-nox) and run 'gnuplot cycle.gp' in {}",
            opt.out, opt.out, opt.out);
      } else if (!plotted) {
        spdlog::warn("gnuplot failed on {}/cycle.gp (see {}/gnuplot.log); the CSV is written",
                     opt.out, opt.out);
      }
      if (status == 0 || status == 127) std::filesystem::remove(dir / "gnuplot.log", ec);
    }
    files_note = opt.out + "/cycle.csv, " + opt.out + "/cycle.gp" +
                 (plotted ? ", drive.svg, drive.png, reactions.svg, reactions.png" : "");
  }
  return files_note;
}

// Step 6a: the --json document (docs/cli.md): the run, the peaks and components, the design
// metrics, the positions (--positions) and the traces.
nlohmann::json CycleRun::json_document() const {
  nlohmann::json j;
  add_run_json(j);
  j["bridges"] = bridges_json();
  j["peaks"] = peaks_json();
  j["components"] = components_json();
  // Design metrics.
  j["loops"] = loops_json();
  if (metrics.power.available) add_power_json(j);
  nlohmann::json about = nlohmann::json::array();
  for (int i = 0; i < model.dimension; ++i) about.push_back(length_u.from_si(shaking.about(i)));
  j["shaking"] = {{"about", about}, {"unit", length_u.name}};
  if (!friction.pins.empty()) add_friction_json(j);
  j["strokes"] = strokes_json();
  j["limits"] = limits_json();
  j["traces"] = traces_json();
  return j;
}

// The document on `out`; with --positions its "points" are written one position at a time
// (io/json_stream.hpp): 1e5 positions were a tree of 1.3 GB for 324 MB of text.
void CycleRun::write_json(std::ostream& out) const {
  nlohmann::json document = json_document();
  if (opt.positions) {
    PositionJson position(model, r, angular, U, noise);
    document["points"] = kJsonStreamPlaceholder;
    write_json_streaming_array(out, document.dump(2), r.points.size(),
                               [&](size_t i) { return position(r.points[i]).dump(2); });
  } else {
    out << document.dump(2);
  }
  out << "\n";
}

// A value at an extreme with its input and time.
nlohmann::json CycleRun::extreme_json(const SeriesExtreme& e, const OutputUnit& u) const {
  return nlohmann::json{{"value", u.from_si(e.value)},
                        {"input", input_u.from_si(e.input)},
                        {"time", time_u.from_si(e.time)}};
}

nlohmann::json CycleRun::events_json(const std::vector<DeadPoint>& v) const {
  nlohmann::json a = nlohmann::json::array();
  for (const DeadPoint& d : v)
    a.push_back({{"input", input_u.from_si(d.input)},
                 {"time", time_u.from_si(d.time)},
                 {"message", d.message}});
  return a;
}

// The run: mechanism, units, status, driver, mobility, redundant rows, dead and singular points.
void CycleRun::add_run_json(nlohmann::json& j) const {
  const Joint& joint = model.joints[static_cast<size_t>(co.driver.joint)];
  j["mechanism"] = model.name;
  j["file"] = model.file;
  j["units"] = units_json(U);
  j["status"] = r.status == CycleStatus::completed               ? "completed"
                : r.status == CycleStatus::stopped_at_dead_point ? "stopped_at_dead_point"
                : r.status == CycleStatus::stopped               ? "stopped"
                                                                 : "failed";
  j["complete"] = r.status != CycleStatus::stopped;
  if (r.status == CycleStatus::stopped) j["stop"] = to_string(r.stop);
  j["message"] = r.message;
  j["driver"] = {{"joint", joint.name},
                 {"name", co.driver.name},
                 {"profile", profile_name(co.driver.profile)},
                 {"speed", speed_u.from_si(co.driver.speed)},
                 {"speed_unit", speed_u.name},
                 {"input_unit", input_u.name},
                 {"drive_unit", unit_of(drive_unit_si).name}};
  j["positions"] = r.points.size();
  j["steps"] = co.steps;
  j["dof"] = r.dof;
  j["rank"] = r.rank;
  nlohmann::json redundant = nlohmann::json::array();
  for (size_t k = 0; k < r.row_names.size(); ++k)
    if (!r.row_determinate.empty() && !r.row_determinate[k]) redundant.push_back(r.row_names[k]);
  j["indeterminate_rows"] = redundant;
  j["chart_switches"] = r.chart_switches;
  j["reversals"] = r.reversals;
  j["dead_points"] = events_json(r.dead_points);
  j["singular_positions"] = events_json(r.singular_positions);
}

nlohmann::json CycleRun::bridges_json() const {
  const OutputUnit drive_out = unit_of(drive_unit_si);
  nlohmann::json bridges = nlohmann::json::array();
  for (const ChangePointBridge& b : r.bridges) {
    nlohmann::json div = nlohmann::json::array();
    for (size_t i = 0; i < r.components.size(); ++i)
      if (b.diverging[i]) div.push_back(r.components[i].name);
    bridges.push_back({{"input", input_u.from_si(b.input)},
                       {"time", time_u.from_si(b.time)},
                       {"time_from", time_u.from_si(b.time_from)},
                       {"time_to", time_u.from_si(b.time_to)},
                       {"drive_error", drive_out.from_si(b.drive_error)},
                       {"diverging", div}});
  }
  return bridges;
}

// peaks: the drive, every reaction magnitude and every reaction component.
// A component zero by construction (a frictionless slide's axial force) is 0, not the
// rounding noise of the solve (io/noise.hpp).
nlohmann::json CycleRun::peaks_json() const {
  nlohmann::json peaks;
  for (const auto* list : {&summary, &shaking_summary, &friction_summary, &component_summary})
    for (const SeriesSummary& s : *list) {
      const OutputUnit u = unit_of(s.unit);
      const Dimension d = dimension_of(s.unit);
      SeriesExtreme max = s.max, min = s.min;
      max.value = noise.clean(d, max.value);
      min.value = noise.clean(d, min.value);
      peaks[s.name] = {{"peak", u.from_si(noise.clean(d, s.peak))},
                       {"input", input_u.from_si(s.peak_input)},
                       {"time", time_u.from_si(s.peak_time)},
                       {"rms", u.from_si(noise.clean(d, s.rms))},
                       {"max", extreme_json(max, u)},
                       {"min", extreme_json(min, u)},
                       {"unit", u.name},
                       {"determinate", s.determinate},
                       {"diverges", s.diverges}};
    }
  return peaks;
}

nlohmann::json CycleRun::components_json() const {
  nlohmann::json comps = nlohmann::json::array();
  for (size_t i = 0; i < r.components.size(); ++i)
    comps.push_back({{"name", r.components[i].name},
                     {"joint", model.joints[static_cast<size_t>(r.components[i].joint)].name},
                     {"frame", r.components[i].global ? "global" : "joint"},
                     {"unit", unit_of(r.components[i].unit).name},
                     {"determinate", r.determinate[i]},
                     {"diverging", r.diverging.empty() ? false : bool(r.diverging[i])}});
  return comps;
}

nlohmann::json CycleRun::loops_json() const {
  nlohmann::json loops = nlohmann::json::array();
  for (const LoopAngleMetric& l : metrics.loops)
    loops.push_back({{"loop", l.loop},
                     {"kind", l.slider_crank ? "slider-crank" : "four-bar"},
                     {"angle", l.slider_crank ? "pressure" : "transmission"},
                     {"min", extreme_json(l.min, angle_u)},
                     {"max", extreme_json(l.max, angle_u)},
                     {"worst", extreme_json(l.worst, angle_u)}});
  return loops;
}

// The drive's power, its energy fluctuation and the flywheel (when asked for).
void CycleRun::add_power_json(nlohmann::json& j) const {
  const PowerMetric& pw = metrics.power;
  j["power"] = {{"mean", power_u.from_si(pw.mean)},
                {"peak", power_u.from_si(pw.peak)},
                {"max", extreme_json(pw.max, power_u)},
                {"min", extreme_json(pw.min, power_u)},
                {"unit", power_u.name}};
  j["energy_fluctuation"] = {{"value", energy_u.from_si(pw.energy_fluctuation)},
                             {"max", extreme_json(pw.energy_max, energy_u)},
                             {"min", extreme_json(pw.energy_min, energy_u)},
                             {"unit", energy_u.name},
                             {"mean_speed", speed_u.from_si(pw.mean_speed)}};
  if (pw.flywheel_inertia)
    j["flywheel"] = {{"speed_fluctuation", opt.speed_fluctuation},
                     {"inertia", inertia_u.from_si(*pw.flywheel_inertia)},
                     {"unit", inertia_u.name}};
}

nlohmann::json CycleRun::strokes_json() const {
  nlohmann::json strokes = nlohmann::json::array();
  for (const StrokeMetric& st : metrics.strokes) {
    const OutputUnit u = unit_of(st.unit);
    nlohmann::json e = {{"name", st.name},
                        {"min", extreme_json(st.min, u)},
                        {"max", extreme_json(st.max, u)},
                        {"range", u.from_si(st.range)},
                        {"unit", u.name}};
    if (st.maxima > 0) e["maxima"] = st.maxima;
    if (st.time_ratio)
      e["time_ratio"] = {{"forward_over_return", *st.time_ratio},
                         {"forward_time", time_u.from_si(st.forward_time)},
                         {"return_time", time_u.from_si(st.return_time)}};
    strokes.push_back(e);
  }
  return strokes;
}

nlohmann::json CycleRun::limits_json() const {
  nlohmann::json limits = nlohmann::json::array();
  for (const LimitExcursion& l : metrics.limits) {
    const Joint& lj = model.joints[static_cast<size_t>(l.joint)];
    const OutputUnit u = output_unit(
        joint_coordinate_kind(lj) == CoordinateKind::angle ? Dimension::angle : Dimension::length,
        U);
    limits.push_back({{"joint", lj.name},
                      {"limits", {u.from_si(lj.limits->x()), u.from_si(lj.limits->y())}},
                      {"first", extreme_json(l.first, u)},
                      {"furthest", extreme_json(l.furthest, u)},
                      {"positions", l.positions},
                      {"unit", u.name}});
  }
  return limits;
}

nlohmann::json CycleRun::traces_json() const {
  nlohmann::json traced = nlohmann::json::array();
  for (const PointTrace& t : traces) {
    nlohmann::json e = {{"point", t.point}, {"unit", length_u.name}};
    std::vector<double> in, x, y;
    for (size_t k = 0; k < t.path.size(); ++k) {
      in.push_back(input_u.from_si(t.input[k]));
      x.push_back(length_u.from_si(t.path[k].x()));
      y.push_back(length_u.from_si(t.path[k].y()));
    }
    e["input"] = in;
    e["x"] = x;
    e["y"] = y;
    if (!t.z.empty()) {
      std::vector<double> z;
      for (const double v : t.z) z.push_back(length_u.from_si(v));
      e["z"] = z;
    }
    traced.push_back(e);
  }
  return traced;
}

// Step 6b: the terminal summary (also the report's): the run, the table of the drive and the
// reaction magnitudes, the design metrics, the traces.
std::string CycleRun::summary_text(const std::string& files_note) const {
  std::ostringstream out;
  summary_run(out);
  summary_events(out);
  if (!files_note.empty()) out << "files           " << files_note << "\n";
  out << "\n";
  summary_table(out);
  summary_metrics(out);
  summary_traces(out);
  summary_indeterminate(out);
  // The joint frame of the components: a planar joint's is its first body's (the second's when
  // the first is the ground); a spatial joint's is its frame f, g, h carried by the first body,
  // fixed in the world when that is the ground (constraints/spatial_joints.cpp).
  out << "\nconvention: reactions are forces and moments on a joint's first body from its "
         "second; "
      << (model.dimension == 3
              ? "Ff ... Mh are in the joint frame f, g, h carried by the first body (fixed in the "
                "world when the first body is the ground). "
              : "\"_local\" and joint-frame components are in the joint's frame (the first "
                "body's, or the second's when the first is the ground). ")
      << "Signed max and min of every component: --json.\n";
  return out.str();
}

// The run: mechanism, driver, the positions swept, status, mobility.
void CycleRun::summary_run(std::ostream& out) const {
  const Joint& joint = model.joints[static_cast<size_t>(co.driver.joint)];
  out << "mechanism       " << model.name << "  (" << model.file << ")\n";
  out << "driver          joint '" << joint.name << "' (" << joint.type_name() << "), "
      << speed_text(co.driver, angular, U) << "\n";
  if (r.points.empty())
    out << "sweep           no position computed\n";
  else
    out << "sweep           " << r.points.size() << " positions, input "
        << format_input(r.points.front().input, angular, U) << " -> "
        << format_input(r.points.back().input, angular, U) << ", t = 0 -> "
        << fmt(time_u.from_si(r.points.back().time)) << " " << time_u.name << "\n";
  out << "status          " << to_string(r.status) << (r.message.empty() ? "" : ": ") << r.message
      << "\n";
  int idle_dof = 0;
  for (const Mobility::Idle& i : r.idle) idle_dof += i.count;
  out << "mobility        DOF " << r.dof;
  if (idle_dof > 0) out << " (" << idle_dof << " idle, held at zero rate)";
  out << ", rank of E " << r.rank << ", "
      << (r.redundant ? std::to_string(r.redundant) + " redundant equation(s)"
                      : std::string("no redundant equations"))
      << "\n";
}

// Dead points, singular positions (and their bridges), joint limits left.
void CycleRun::summary_events(std::ostream& out) const {
  out << "dead points     " << (r.dead_points.empty() ? "none" : "") << "\n";
  for (const DeadPoint& d : r.dead_points)
    out << "  t = " << fmt(time_u.from_si(d.time), 6) << " " << time_u.name << ": " << d.message
        << "\n";
  out << "singular        " << (r.singular_positions.empty() ? "none" : "") << "\n";
  for (const DeadPoint& d : r.singular_positions)
    out << "  at input " << format_input(d.input, angular, U) << ": passed (E loses rank)\n";
  for (const ChangePointBridge& b : r.bridges) {
    int diverging = 0;
    for (const bool x : b.diverging) diverging += x ? 1 : 0;
    const OutputUnit du = unit_of(drive_unit_si);
    out << "  bridged at " << format_input(b.input, angular, U) << ": values within "
        << format_input(std::abs(b.time_to - b.time) * std::abs(co.driver.speed), angular, U)
        << " from the branch (drive error estimate " << fmt(du.from_si(b.drive_error), 2) << " "
        << du.name << "; " << diverging << " diverging component(s) not reported there)\n";
  }
  out << "limits          " << (metrics.limits.empty() ? "kept" : "") << "\n";
  for (const LimitExcursion& l : metrics.limits) {
    const Joint& lj = model.joints[static_cast<size_t>(l.joint)];
    const bool rev = joint_coordinate_kind(lj) == CoordinateKind::angle;
    out << "  joint '" << lj.name << "' leaves its limits [" << format_input(lj.limits->x(), rev, U)
        << ", " << format_input(lj.limits->y(), rev, U) << "] at input "
        << format_input(wrapped(l.first.input), angular, U) << " and reaches "
        << format_input(l.furthest.value, rev, U) << " at input "
        << format_input(wrapped(l.furthest.input), angular, U) << " (" << l.positions
        << " positions outside)\n";
  }
}

// The table of the drive and the reaction magnitudes: columns sized to the longest name.
void CycleRun::summary_table(std::ostream& out) const {
  size_t name_w = 8, unit_w = 4;
  for (const SeriesSummary& s : summary) {
    name_w = std::max(name_w, s.name.size());
    unit_w = std::max(unit_w, unit_of(s.unit).name.size());
  }
  char line[400];
  const int nw = static_cast<int>(name_w), uw = static_cast<int>(unit_w);
  std::snprintf(line, sizeof line, "%-*s  %-*s %12s %14s %12s %14s %12s\n", nw, "quantity", uw,
                "unit", "max", "at input", "min", "at input", "RMS");
  out << line;
  for (const SeriesSummary& s : summary) {
    if (s.samples == 0) continue;
    const OutputUnit u = unit_of(s.unit);
    std::snprintf(line, sizeof line, "%-*s  %-*s %12.5g %14s %12.5g %14s %12.5g%s\n", nw,
                  s.name.c_str(), uw, u.name.c_str(),
                  u.from_si(noise.clean(dimension_of(s.unit), s.max.value)),
                  format_input(wrapped(s.max.input), angular, U).c_str(),
                  u.from_si(noise.clean(dimension_of(s.unit), s.min.value)),
                  format_input(wrapped(s.min.input), angular, U).c_str(),
                  u.from_si(noise.clean(dimension_of(s.unit), s.rms)),
                  s.determinate ? ""
                  : s.diverges  ? "   indeterminate (minimum norm), diverges at a change point"
                                : "   indeterminate (minimum norm)");
    out << line;
  }
}

// Design metrics: transmission and pressure angles, drive power and flywheel, the shaking
// moment's point, strokes.
void CycleRun::summary_metrics(std::ostream& out) const {
  out << "\n";
  for (const LoopAngleMetric& l : metrics.loops) {
    if (l.slider_crank)
      out << "pressure angle      loop " << l.loop << ": max " << format_input(l.max.value, true, U)
          << " at input " << format_input(wrapped(l.max.input), angular, U) << "\n";
    else
      out << "transmission angle  loop " << l.loop << ": " << format_input(l.min.value, true, U)
          << " ... " << format_input(l.max.value, true, U) << "; worst "
          << format_input(l.worst.value, true, U) << " from a straight line at input "
          << format_input(wrapped(l.worst.input), angular, U) << "\n";
  }
  if (metrics.power.available) {
    const PowerMetric& pw = metrics.power;
    out << "drive power         mean " << fmt(power_u.from_si(pw.mean), 5) << " " << power_u.name
        << ", max " << fmt(power_u.from_si(pw.max.value), 5) << " at input "
        << format_input(wrapped(pw.max.input), angular, U) << ", min "
        << fmt(power_u.from_si(pw.min.value), 5) << " at input "
        << format_input(wrapped(pw.min.input), angular, U) << "\n";
    out << "energy fluctuation  " << fmt(energy_u.from_si(pw.energy_fluctuation), 5) << " "
        << energy_u.name << " (max - min of the integral of drive power minus its mean)\n";
    if (pw.flywheel_inertia)
      out << "flywheel            " << fmt(inertia_u.from_si(*pw.flywheel_inertia), 5) << " "
          << inertia_u.name << " on the input for a speed fluctuation of "
          << fmt(opt.speed_fluctuation) << "\n";
  }
  summary_shaking(out);
  summary_friction(out);
  for (const StrokeMetric& st : metrics.strokes) {
    const OutputUnit u = unit_of(st.unit);
    out << "range  " << st.name << ": " << fmt(u.from_si(st.min.value), 7) << " ... "
        << fmt(u.from_si(st.max.value), 7) << " " << u.name << " (stroke "
        << fmt(u.from_si(st.range), 7) << ")";
    if (st.time_ratio) out << ", time ratio forward/return " << fmt(*st.time_ratio, 6);
    if (st.maxima > 1) out << ", " << st.maxima << " maxima per cycle: no time ratio";
    out << "\n";
  }
}

// The shaking force and moment: extremes, RMS and the point of the moment.
void CycleRun::summary_shaking(std::ostream& out) const {
  for (const SeriesSummary& s : shaking_summary) {
    if (s.samples == 0) continue;
    const OutputUnit u = unit_of(s.unit);
    const Dimension d = dimension_of(s.unit);
    const bool is_force = d == Dimension::force;
    out << (is_force ? "shaking force       max " : "shaking moment      max ")
        << fmt(u.from_si(noise.clean(d, s.max.value)), 5) << " at input "
        << format_input(wrapped(s.max.input), angular, U);
    if (s.min.value < 0.0)
      out << ", min " << fmt(u.from_si(noise.clean(d, s.min.value)), 5) << " at input "
          << format_input(wrapped(s.min.input), angular, U);
    out << ", RMS " << fmt(u.from_si(noise.clean(d, s.rms)), 5) << " " << u.name;
    if (!is_force) {
      out << " about (";
      for (int i = 0; i < model.dimension; ++i)
        out << (i ? ", " : "") << fmt(length_u.from_si(shaking.about(i)), 7);
      out << ") " << length_u.name;
    }
    out << (is_force ? " (the inertia forces of the moving bodies on the frame; it also carries "
                       "the static loads)\n"
                     : "\n");
  }
}

// The pins' friction: the drive without it, the dissipated energy, each pin's moment.
void CycleRun::summary_friction(std::ostream& out) const {
  if (friction.pins.empty()) return;
  const OutputUnit drive_u = unit_of(drive_unit_si);
  for (const SeriesSummary& s : friction_summary) {
    if (s.samples == 0) continue;
    const OutputUnit u = unit_of(s.unit);
    out << "friction  " << s.name << ": max " << fmt(u.from_si(s.max.value), 5) << ", min "
        << fmt(u.from_si(s.min.value), 5) << ", RMS " << fmt(u.from_si(s.rms), 5) << " " << u.name
        << "\n";
  }
  out << "friction  dissipated " << fmt(energy_u.from_si(friction.dissipated), 5) << " "
      << energy_u.name << " over the sweep (drive RMS " << fmt(drive_u.from_si(summary[0].rms), 5)
      << " " << drive_u.name << " with friction)\n";
  if (std::isfinite(friction.efficiency))
    out << "friction  efficiency " << fmt(friction.efficiency, 5)
        << " = W0/W: the drive's net work "
        << fmt(energy_u.from_si(friction.drive_work_frictionless), 5) << " " << energy_u.name
        << " without friction, " << fmt(energy_u.from_si(friction.drive_work), 5) << " "
        << energy_u.name << " with it\n";
  else
    out << "friction  efficiency not applicable: the loads take no net work from the drive over "
           "the sweep (W0 = "
        << fmt(energy_u.from_si(friction.drive_work_frictionless), 5) << " " << energy_u.name
        << ")\n";
  for (size_t i = 0; i < friction.pins.size(); ++i)
    if (!friction.determinate[i])
      out << "friction  " << model.joints[static_cast<size_t>(friction.pins[i].joint)].name
          << ": not determined (its force is statically indeterminate; the minimum-norm force's "
             "friction is reported)\n";
  summary_friction_bound(out);
}

// The least friction over the admissible splits of the redundant reactions.
void CycleRun::summary_friction_bound(std::ostream& out) const {
  const FrictionSeries::LowerBound& b = friction.bound;
  if (!b.computed) return;
  if (b.unsolved > 0) {
    out << "friction  least over the admissible splits: not found at " << b.unsolved
        << " positions (Ipopt did not converge)\n";
    return;
  }
  const long positions = std::count(b.reported.begin(), b.reported.end(), true);
  out << "friction  least over the admissible splits of the redundant reactions: dissipated "
      << fmt(energy_u.from_si(b.dissipated), 5) << " " << energy_u.name << ", drive's net work "
      << fmt(energy_u.from_si(b.drive_work), 5) << " " << energy_u.name << " (over " << positions
      << " of " << r.points.size() << " positions"
      << (positions < static_cast<long>(r.points.size())
              ? ": those bridged next to change points are left out)\n"
              : ")\n");
}

// The pins' friction in the JSON document.
void CycleRun::add_friction_json(nlohmann::json& j) const {
  nlohmann::json pins = nlohmann::json::array();
  for (size_t i = 0; i < friction.pins.size(); ++i) {
    const FrictionPin& p = friction.pins[i];
    pins.push_back({{"joint", model.joints[static_cast<size_t>(p.joint)].name},
                    {"coefficient", p.coefficient},
                    {"radius", length_u.from_si(p.radius)},
                    {"determinate", bool(friction.determinate[i])}});
  }
  j["friction"] = {
      {"joints", pins},
      {"dissipated", energy_u.from_si(friction.dissipated)},
      {"drive_work", energy_u.from_si(friction.drive_work)},
      {"drive_work_frictionless", energy_u.from_si(friction.drive_work_frictionless)},
      {"efficiency", std::isfinite(friction.efficiency) ? nlohmann::json(friction.efficiency)
                                                        : nlohmann::json(nullptr)},
      {"unit", energy_u.name},
      {"iterations_max", friction.iterations_max},
      {"converged", friction.converged},
      {"lower_bound", nullptr}};
  const FrictionSeries::LowerBound& b = friction.bound;
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  if (b.computed)
    j["friction"]["lower_bound"] = {
        {"dissipated", number(energy_u.from_si(b.dissipated))},
        {"drive_work", number(energy_u.from_si(b.drive_work))},
        {"positions", std::count(b.reported.begin(), b.reported.end(), true)},
        {"unsolved", b.unsolved}};
}

// The box of every traced point's path.
void CycleRun::summary_traces(std::ostream& out) const {
  for (const PointTrace& t : traces) {
    Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Vec2& p : t.path) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    out << "trace  " << t.point << ": x " << fmt(length_u.from_si(lo.x()), 7) << " ... "
        << fmt(length_u.from_si(hi.x()), 7) << ", y " << fmt(length_u.from_si(lo.y()), 7) << " ... "
        << fmt(length_u.from_si(hi.y()), 7);
    if (!t.z.empty()) {
      const auto [zlo, zhi] = std::minmax_element(t.z.begin(), t.z.end());
      out << ", z " << fmt(length_u.from_si(*zlo), 7) << " ... " << fmt(length_u.from_si(*zhi), 7);
    }
    out << " " << length_u.name << "\n";
  }
}

// The statically indeterminate reaction components, if any.
void CycleRun::summary_indeterminate(std::ostream& out) const {
  bool any = false;
  for (size_t i = 0; i < r.components.size(); ++i) {
    if (r.determinate[i]) continue;
    out << (any ? ", "
                : "\nstatically indeterminate components (minimum-norm values "
                  "reported; any value in a family balances the loads):\n  ")
        << r.components[i].name;
    any = true;
  }
  if (any) out << "\n";
}

// Step 7: the pictures of --animate and --report: one animation of the cycle's positions
// (render's animated_svg), in the report too with the summary and the plots.
void CycleRun::write_pictures(const Projection& projection, const std::string& text) const {
  RenderOptions ro;
  ro.driver = co.driver.joint;
  ro.projection = projection;
  ro.traces = traces;
  std::string animation;
  try {
    animation = animated_svg(model, sweep.q, ro, opt.duration);
    if (!opt.animate.empty()) {
      write_file(opt.animate, animation);
      spdlog::info("wrote {} ({} frames of {} positions)", opt.animate,
                   picture_positions(sweep.q.size()).size(), sweep.q.size());
    }
    if (!opt.report.empty()) {
      CycleReport report;
      report.title = model.name;
      report.summary = text;
      report.input_label = "input [" + input_u.name + "]";
      for (const double s : sweep.input) report.input.push_back(input_u.from_si(s));
      report.plots = report_plots(model, r, magnitudes, shaking, angular, U);
      report.animation = std::move(animation);
      report.duration = opt.duration;
      write_file(opt.report, cycle_report_html(report));
      spdlog::info("wrote {} ({} positions)", opt.report, sweep.q.size());
    }
  } catch (const std::runtime_error& e) {
    release_render_caches();
    throw CLI::ValidationError(opt.report.empty() ? "--animate" : "--report", e.what());
  }
  release_render_caches();
}

int run_cycle_command(const CycleCliOptions& opt) {
  const Model model = load(opt.file, opt.sets);
  if (!opt.drivers.empty()) {  // several drivers: cli/cycle_drivers.cpp
    DriversRequest request;
    request.drivers = opt.drivers;
    request.t_end = opt.t_end;
    request.steps = opt.steps;
    request.json = opt.json;
    request.units = opt.units;
    request.out = opt.out;
    return run_cycle_drivers(model, request);
  }
  // Step 1: the request (units, pictures' view, traced points, driver and range).
  const UnitSystem U = resolve_units(model, opt.units);
  if (!opt.animate.empty() && image_format_of(opt.animate) != ImageFormat::svg)
    throw CLI::ValidationError("--animate", "the animation is an SVG: give a NAME.svg");
  const ViewChoice view = choose_view(model, opt.view);
  if (!view.projection) throw InputError({"command line", 0, 0}, "option", view.message);
  const TracePoints trace_request = resolve_trace_points(model, opt.traces);
  if (trace_request.status == TraceStatus::bad_request)
    throw InputError({"command line", 0, 0}, "option", trace_request.message);
  const CycleOptions request = cycle_request(model, opt, U);

  // Step 2: the sweep, bounded (run_bounds.hpp): --time-limit, SIGINT/SIGTERM as a clean stop
  // (what was swept is written, marked incomplete), a progress line on a terminal's stderr.
  CycleOptions co = request;
  co.control = run_control("cycle", opt.time_limit);
  const CycleResult r = run_bounded([&] { return run_cycle(model, co); });

  // Summaries, metrics, traced points and units of what the sweep found.
  const bool angular = is_angular(model, co.driver.joint);
  CycleRun c{opt, model, co, r, angular, U};
  c.drive_unit_si = angular ? "N*m" : "N";
  c.magnitudes = reaction_magnitudes(r);
  c.summary = summarize_cycle(r, c.magnitudes, c.drive_unit_si);
  c.component_summary = summarize_components(r);
  c.shaking = shaking_series(model, r, parse_point(model, opt.shaking_about, "--shaking-about"));
  ShakingSummaries shaking = summarize_shaking(model, r, c.shaking);
  c.shaking_summary = std::move(shaking.magnitudes);
  c.friction =
      friction_series(model, r, co.driver.joint,
                      co.full_cycle && r.status == CycleStatus::completed && r.reversals == 0);
  c.friction_summary = summarize_friction(model, r, c.friction, c.drive_unit_si);
  for (SeriesSummary& s : shaking.components) c.component_summary.push_back(std::move(s));
  CycleMetricsOptions mo;
  mo.driver_joint = co.driver.joint;
  mo.full_cycle = co.full_cycle;
  if (opt.speed_fluctuation > 0.0) mo.speed_fluctuation = opt.speed_fluctuation;
  c.metrics = compute_cycle_metrics(model, r, mo);

  // Step 3: a rejected request or an empty sweep ends the run here.
  if (const std::optional<int> code = check_cycle_outcome(model, opt, co, r)) return *code;
  // Step 4: the log.
  c.log_cycle();

  c.set_output_units();
  // The traced points over the cycle's own positions.
  c.sweep = sweep_positions_of(r);
  c.traces = trace_paths(model, trace_request, c.sweep.q, c.sweep.input);

  // Step 5: files first.
  const std::string files_note = c.write_files();
  // Step 6: the results (stdout): the JSON document or the terminal summary.
  c.noise = cycle_noise_floor(model, r, c.magnitudes, angular);
  const std::string summary = c.summary_text(files_note);
  // Step 7: the pictures.
  if (!opt.animate.empty() || !opt.report.empty()) c.write_pictures(*view.projection, summary);
  if (opt.json)
    c.write_json(std::cout);
  else
    std::cout << summary;  // all at once
  if (!c.friction.converged) {
    spdlog::error(
        "{}: the friction moments did not settle at some positions (the fixed point of the pin "
        "forces and their friction did not converge: the friction radius or coefficient is too "
        "large for the linkage's lever arms); the friction values are not reliable",
        model.file);
    return kNumerical;
  }
  return r.status == CycleStatus::completed               ? kOk
         : r.status == CycleStatus::stopped_at_dead_point ? kCheckFailed
         : r.status == CycleStatus::stopped               ? kStopped
                                                          : kNumerical;
}

}  // namespace

void register_cycle(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<CycleCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "cycle",
      "driven sweep over one cycle: drive torque/force and every joint's reaction per position; "
      "peaks and RMS; dead points; CSV and plots");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  add_set_option(cmd, opt->sets);
  cmd->add_option("--driver", opt->driver,
                  "driven joint (default: the file's analysis.driver, else its first driver)");
  cmd->add_option("--speed", opt->speed,
                  "constant input speed, e.g. 300rpm, 31.4rad/s, 90deg/s, 0.5m/s; a bare number is "
                  "in the file's angle (or length) unit per time unit");
  cmd->add_option("--steps", opt->steps, "positions per cycle (default: the file's, else 360)")
      ->check(CLI::Range(2, kMaxCycleSteps));
  cmd->add_option("--from", opt->from,
                  "start input, e.g. 30deg, 20mm; a bare number is in the file's declared units");
  cmd->add_option("--to", opt->to,
                  "end input: sweep the range instead of a full turn (units as --from)");
  cmd->add_option("--drivers", opt->drivers,
                  "several drivers at once (names of the file's drivers or their joints, "
                  "comma-separated): one per degree of freedom, each with its own time law; "
                  "swept over --t-end or one period of the slowest law")
      ->delimiter(',');
  cmd->add_option("--t-end", opt->t_end, "with --drivers: end of the sweep (s)")
      ->check(finite_range(0.0, kMaxGeneral, true));
  cmd->add_flag("--reverse-at-dead-point", opt->reverse,
                "at a dead point, pass it and drive the input back (sweeps a rocker's closed "
                "curve)");
  cmd->add_option("--time-limit", opt->time_limit,
                  "wall-clock limit in seconds (default: none): the sweep stops there with status "
                  "stopped and writes the positions swept, exit 5")
      ->check(finite_range(0.0, 1e9, true));
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  cmd->add_flag(
      "--positions", opt->positions,
      "with --json: every position too (body poses, named points, velocities, reactions)");
  cmd->add_option("--speed-fluctuation", opt->speed_fluctuation,
                  "coefficient of speed fluctuation C_s (e.g. 0.02): report the flywheel inertia "
                  "on the input that keeps it; 1e-6 to 1")
      ->check(finite_range(kMinSpeedFluctuation, 1.0));
  add_units_option(cmd, opt->units);
  cmd->add_option("--out", opt->out, "directory for cycle.csv, cycle.gp and the plots");
  cmd->add_option("--trace", opt->traces,
                  "BODY.POINT: the path of this point over the cycle (CSV columns, JSON "
                  "\"traces\", drawn in --animate and --report); repeatable");
  cmd->add_option("--animate", opt->animate,
                  "FILE.svg: an SVG that plays the cycle by itself, one frame per position");
  cmd->add_option("--report", opt->report,
                  "FILE.html: one self-contained page (offline): the summary, the drive and "
                  "reaction plots and the animation with a slider");
  cmd->add_option("--view", opt->view,
                  "the pictures of a spatial mechanism (--animate, --report): iso (default), "
                  "front, top, side, or AZIMUTH,ELEVATION in degrees (orthographic)");
  cmd->add_option("--duration", opt->duration,
                  "seconds of one loop of the animation (--animate, --report; default 4)")
      ->check(finite_range(0.0, 3600.0, true));
  cmd->add_option("--shaking-about", opt->shaking_about,
                  "X,Y (planar) or X,Y,Z (spatial) in the file's length unit: the point of the "
                  "frame about which the shaking moment is taken (default: the origin)");
  cmd->add_flag("-q,--quiet", opt->quiet, "no progress and only errors on stderr");
  cmd->add_flag("-v,--verbose", opt->verbose, "debug messages on stderr (also before the command)");
  cmd->callback([opt, &globals, &exit_code] {
    GlobalOptions g = globals;
    g.quiet = g.quiet || opt->quiet;
    g.verbose = g.verbose || opt->verbose;
    setup_logging(g);
    exit_code = run_cycle_command(*opt);
  });
}

}  // namespace orthomech::cli

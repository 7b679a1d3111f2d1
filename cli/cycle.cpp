// `orthomech cycle FILE`: a driven mechanism swept through one cycle of its input — drive
// torque/force and every joint's reaction at every position, peaks and RMS, dead points, chart
// switches, which reaction components are unique (design §6, docs/cli.md). No math here: the
// sweep is run_cycle (analysis/cycle.hpp), the files are io/cycle_output.hpp.
#include "orthomech/analysis/cycle.hpp"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/cycle_output.hpp"
#include "orthomech/io/units.hpp"

namespace orthomech::cli {

namespace {

struct CycleCliOptions {
  std::string file;
  std::string driver;  // joint (or driver) name
  std::string speed;
  std::string from, to;
  int steps = 0;  // 0: the file's analysis.steps
  bool json = false;
  bool positions = false;
  std::string out;
  bool quiet = false;
  bool reverse = false;
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
  return std::holds_alternative<Revolute>(model.joints[static_cast<size_t>(joint)].kind);
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
    if (!std::holds_alternative<Revolute>(j.kind) && !std::holds_alternative<Prismatic>(j.kind))
      throw CLI::ValidationError("--driver", "joint '" + j.name + "' is a " + j.type_name() +
                                                 " joint; a driver needs a revolute or prismatic "
                                                 "joint");
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
      driver.speed = parse_speed(opt.speed, is_angular(model, driver.joint), 1.0);
    } catch (const std::invalid_argument& e) {
      throw CLI::ValidationError("--speed", e.what());
    }
    if (driver.speed == 0.0) throw CLI::ValidationError("--speed", "the speed must not be zero");
    driver.profile = Profile::constant_speed;
  }
  return driver;
}

std::string speed_text(const Driver& d, bool angular) {
  if (d.profile == Profile::harmonic)
    return "harmonic, amplitude " + format_input(d.amplitude, angular) + " about " +
           format_input(d.initial, angular) + ", " + fmt(d.frequency) + " Hz";
  if (d.profile == Profile::polynomial) return "polynomial";
  return angular ? "constant speed " + fmt(d.speed * 60.0 / (2.0 * std::numbers::pi)) + " rpm (" +
                       fmt(d.speed) + " rad/s)"
                 : "constant speed " + fmt(d.speed) + " m/s";
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

nlohmann::json positions_json(const Model& model, const CycleResult& r) {
  nlohmann::json pts = nlohmann::json::array();
  for (const DrivenPointView& p : r.points) {
    nlohmann::json j;
    j["input"] = p.input;
    j["time"] = p.time;
    j["singular"] = p.singular;
    j["bridged"] = p.bridge >= 0;
    nlohmann::json m = nlohmann::json::object();
    for (size_t i = 0; i < model.measures.size(); ++i) m[model.measures[i].name] = p.measures[i];
    j["measures"] = m;
    // Velocities and accelerations of every body's centre of mass (and angular ones).
    nlohmann::json bodies = nlohmann::json::object();
    for (const Body& b : model.bodies) {
      const auto v = p.u.segment(b.u_offset, b.nu());
      const auto a = p.udot.segment(b.u_offset, b.nu());
      bodies[b.name] = {{"velocity", std::vector<double>(v.data(), v.data() + v.size())},
                        {"acceleration", std::vector<double>(a.data(), a.data() + a.size())}};
    }
    j["bodies"] = bodies;
    if (drive_reported(p)) {  // not at a change point that could not be bridged
      j["drive"] = p.drive;
      nlohmann::json rc = nlohmann::json::object();
      for (size_t i = 0; i < r.components.size(); ++i)
        if (component_reported(r, p, i)) rc[r.components[i].name] = p.reactions[i];
      j["reactions"] = rc;
    }
    j["kinetic_energy"] = p.kinetic;
    j["potential_energy"] = p.potential;
    pts.push_back(j);
  }
  return pts;
}

int run_cycle_command(const CycleCliOptions& opt, const GlobalOptions& globals) {
  const Model model = load(opt.file);
  CycleOptions co;
  co.driver = resolve_driver(model, opt);
  const bool angular = is_angular(model, co.driver.joint);
  const std::string drive_unit = angular ? "N*m" : "N";
  co.steps = opt.steps > 0 ? opt.steps : model.analysis.steps;
  co.reverse_at_dead_point = opt.reverse;
  try {
    if (!opt.from.empty()) {
      co.use_start = true;
      co.start = parse_position(opt.from, angular, 1.0);
    }
    if (!opt.to.empty()) {
      co.full_cycle = false;
      co.end = parse_position(opt.to, angular, 1.0);
    }
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError(opt.from.empty() ? "--to" : "--from/--to", e.what());
  }
  if (!opt.from.empty() && opt.to.empty() && !angular)
    throw CLI::ValidationError("--to", "a prismatic driver needs the end of the range (--to)");

  // Progress on stderr for sweeps longer than a second, only on a terminal and not when quiet.
  const bool show_progress = !opt.quiet && !globals.quiet && isatty(STDERR_FILENO) != 0;
  const auto started = std::chrono::steady_clock::now();
  bool progress_shown = false;
  if (show_progress) {
    co.progress = [&](double fraction) {
      if (std::chrono::steady_clock::now() - started < std::chrono::seconds(1)) return;
      std::fprintf(stderr, "\rcycle: %3.0f %%", 100.0 * fraction);
      std::fflush(stderr);
      progress_shown = true;
    };
  }
  const CycleResult r = run_cycle(model, co);
  if (progress_shown) std::fprintf(stderr, "\r\033[K");
  const std::vector<ReactionMagnitude> magnitudes = reaction_magnitudes(r);
  const std::vector<SeriesSummary> summary = summarize_cycle(r, magnitudes, drive_unit);
  const Joint& joint = model.joints[static_cast<size_t>(co.driver.joint)];

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
  if (r.status == CycleStatus::failed)
    spdlog::error("{}: the sweep stopped: {}", model.file, r.message);
  for (const std::string& w : r.warnings) spdlog::warn("{}: {}", model.file, w);
  if (r.status == CycleStatus::stopped_at_dead_point) spdlog::warn("{}: {}", model.file, r.message);
  for (const DeadPoint& d : r.singular_positions) spdlog::info("{}", d.message);

  // Files first: a failure to write is reported before anything goes to stdout.
  std::string files_note;
  if (!opt.out.empty()) {
    const std::filesystem::path dir(opt.out);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw CLI::ValidationError("--out", "cannot create " + opt.out + ": " + ec.message());
    try {
      const CycleColumns cols =
          write_cycle_csv(dir / "cycle.csv", model, r, magnitudes, angular, drive_unit);
      write_cycle_gnuplot(dir / "cycle.gp", "cycle.csv", model, magnitudes, cols, angular,
                          drive_unit);
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

  std::ostringstream out;
  if (opt.json) {
    nlohmann::json j;
    j["mechanism"] = model.name;
    j["file"] = model.file;
    j["status"] = r.status == CycleStatus::completed               ? "completed"
                  : r.status == CycleStatus::stopped_at_dead_point ? "stopped_at_dead_point"
                                                                   : "failed";
    j["message"] = r.message;
    j["driver"] = {{"joint", joint.name},
                   {"name", co.driver.name},
                   {"profile", profile_name(co.driver.profile)},
                   {"speed", co.driver.speed},
                   {"input_unit", angular ? "rad" : "m"},
                   {"drive_unit", drive_unit}};
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
    auto events = [](const std::vector<DeadPoint>& v) {
      nlohmann::json a = nlohmann::json::array();
      for (const DeadPoint& d : v)
        a.push_back({{"input", d.input}, {"time", d.time}, {"message", d.message}});
      return a;
    };
    j["dead_points"] = events(r.dead_points);
    j["singular_positions"] = events(r.singular_positions);
    nlohmann::json bridges = nlohmann::json::array();
    for (const ChangePointBridge& b : r.bridges) {
      nlohmann::json div = nlohmann::json::array();
      for (size_t i = 0; i < r.components.size(); ++i)
        if (b.diverging[i]) div.push_back(r.components[i].name);
      bridges.push_back({{"input", b.input},
                         {"time", b.time},
                         {"time_from", b.time_from},
                         {"time_to", b.time_to},
                         {"drive_error", b.drive_error},
                         {"diverging", div}});
    }
    j["bridges"] = bridges;
    nlohmann::json peaks;
    for (const SeriesSummary& s : summary)
      peaks[s.name] = {
          {"peak", s.peak}, {"input", s.peak_input},        {"time", s.peak_time},   {"rms", s.rms},
          {"unit", s.unit}, {"determinate", s.determinate}, {"diverges", s.diverges}};
    j["peaks"] = peaks;
    nlohmann::json comps = nlohmann::json::array();
    for (size_t i = 0; i < r.components.size(); ++i)
      comps.push_back({{"name", r.components[i].name},
                       {"joint", model.joints[static_cast<size_t>(r.components[i].joint)].name},
                       {"frame", r.components[i].global ? "global" : "joint"},
                       {"unit", r.components[i].unit},
                       {"determinate", r.determinate[i]},
                       {"diverging", r.diverging.empty() ? false : bool(r.diverging[i])}});
    j["components"] = comps;
    if (opt.positions) j["points"] = positions_json(model, r);
    out << j.dump(2) << '\n';
  } else {
    out << "mechanism       " << model.name << "  (" << model.file << ")\n";
    out << "driver          joint '" << joint.name << "' (" << joint.type_name() << "), "
        << speed_text(co.driver, angular) << "\n";
    if (r.points.empty())
      out << "sweep           no position computed\n";
    else
      out << "sweep           " << r.points.size() << " positions, input "
          << format_input(r.points.front().input, angular) << " -> "
          << format_input(r.points.back().input, angular) << ", t = 0 -> "
          << fmt(r.points.back().time) << " s\n";
    out << "status          " << to_string(r.status) << (r.message.empty() ? "" : ": ") << r.message
        << "\n";
    out << "mobility        DOF " << r.dof << ", rank of E " << r.rank << ", "
        << (r.redundant ? std::to_string(r.redundant) + " redundant equation(s)"
                        : std::string("no redundant equations"))
        << "\n";
    out << "chart switches  " << r.chart_switches << "\n";
    out << "dead points     " << (r.dead_points.empty() ? "none" : "") << "\n";
    for (const DeadPoint& d : r.dead_points)
      out << "  t = " << fmt(d.time, 6) << " s: " << d.message << "\n";
    out << "singular        " << (r.singular_positions.empty() ? "none" : "") << "\n";
    for (const DeadPoint& d : r.singular_positions)
      out << "  at input " << format_input(d.input, angular) << ": passed (E loses rank)\n";
    for (const ChangePointBridge& b : r.bridges) {
      int diverging = 0;
      for (const bool x : b.diverging) diverging += x ? 1 : 0;
      out << "  bridged at " << format_input(b.input, angular) << ": values within "
          << format_input(std::abs(b.time_to - b.time) * std::abs(co.driver.speed), angular)
          << " from the branch (drive error estimate " << fmt(b.drive_error, 2) << " " << drive_unit
          << "; " << diverging << " diverging component(s) not reported there)\n";
    }
    if (!files_note.empty()) out << "files           " << files_note << "\n";
    out << "\n";
    // Angles at peaks in [0°, 360°) (the sweep line keeps the continuous input).
    auto wrapped = [angular](double s) {
      if (!angular) return s;
      double w = std::fmod(s, 2.0 * std::numbers::pi);
      if (w < 0.0) w += 2.0 * std::numbers::pi;
      return w > 2.0 * std::numbers::pi - 1e-9 ? 0.0 : w;
    };
    char line[200];
    std::snprintf(line, sizeof line, "%-20s %-5s %13s %16s %13s\n", "quantity", "unit", "peak",
                  "at input", "RMS");
    out << line;
    for (const SeriesSummary& s : summary) {
      if (s.samples == 0) continue;
      std::snprintf(line, sizeof line, "%-20s %-5s %13.5g %16s %13.5g%s\n", s.name.c_str(),
                    s.unit.c_str(), s.peak, format_input(wrapped(s.peak_input), angular).c_str(),
                    s.rms,
                    s.determinate ? ""
                    : s.diverges  ? "   indeterminate (minimum norm), diverges at a change point"
                                  : "   indeterminate (minimum norm)");
      out << line;
    }
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
    out << "\nconvention: reactions are forces and moments on a joint's first body from its "
           "second; \"_local\" and joint-frame components are in the joint's frame (the first "
           "body's, or the second's when the first is the ground).\n";
  }
  std::cout << out.str();  // all at once
  return r.status == CycleStatus::completed               ? kOk
         : r.status == CycleStatus::stopped_at_dead_point ? kCheckFailed
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
  cmd->add_option("--driver", opt->driver,
                  "driven joint (default: the file's analysis.driver, else its first driver)");
  cmd->add_option("--speed", opt->speed,
                  "constant input speed, e.g. 300rpm, 31.4rad/s, 90deg/s, 0.5m/s (bare: SI)");
  cmd->add_option("--steps", opt->steps, "positions per cycle (default: the file's, else 360)")
      ->check(CLI::Range(2, kMaxCycleSteps));
  cmd->add_option("--from", opt->from, "start input, e.g. 30deg, 20mm (bare: SI)");
  cmd->add_option("--to", opt->to, "end input: sweep the range instead of a full turn");
  cmd->add_flag("--reverse-at-dead-point", opt->reverse,
                "at a dead point, pass it and drive the input back (sweeps a rocker's closed "
                "curve)");
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  cmd->add_flag("--positions", opt->positions, "with --json: every position too");
  cmd->add_option("--out", opt->out, "directory for cycle.csv, cycle.gp and the plots");
  cmd->add_flag("--quiet", opt->quiet, "no progress and only errors on stderr");
  cmd->callback([opt, &globals, &exit_code] {
    GlobalOptions g = globals;
    g.quiet = g.quiet || opt->quiet;
    setup_logging(g);
    exit_code = run_cycle_command(*opt, g);
  });
}

}  // namespace orthomech::cli

// `orthomech assemble FILE`: projects the design position onto the constraint manifold (Ipopt,
// analysis/assembly.hpp), reports how far each body moved, the joint residuals, the solver
// status, the measures at the assembled position and the initial velocities u = α u₀; with
// --write saves a mechanism file whose design position is the assembled one (docs/cli.md).
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/validate.hpp"
#include "orthomech/io/mechanism_writer.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/measures.hpp"

namespace orthomech::cli {

namespace {

struct AssembleOptions {
  std::string file;
  std::vector<std::string> sets;  // --set PATH=VALUE
  bool json = false;
  std::vector<std::string> locks;
  std::vector<std::string> velocities;
  std::string position;
  bool no_limits = false;
  std::string write;
  bool in_place = false;
  double tolerance = 1e-12;
  std::string units = "file";
};

std::string fmt(double v, int precision = 6) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

[[noreturn]] void bad(const std::string& what) {
  throw InputError({"command line", 0, 0}, "option", what);
}

// "A0=30deg", "A0=30" (the file's angle or length unit), "P=12mm": a lock value with an
// optional unit.
JointLock parse_lock(const Model& model, const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos) bad("--lock expects JOINT=VALUE, got '" + text + "'");
  const std::string name = text.substr(0, eq);
  const int j = model.find_joint(name);
  if (j < 0) bad("--lock: joint '" + name + "' is not defined");
  const auto& kind = model.joints[static_cast<size_t>(j)].kind;
  const bool angular = std::holds_alternative<Revolute>(kind);
  if (!angular && !std::holds_alternative<Prismatic>(kind))
    bad("--lock: joint '" + name + "' is neither revolute nor prismatic and has no coordinate");
  const UnitSystem file = unit_system(model.units);
  try {
    return {j,
            parse_position(text.substr(eq + 1), angular, angular ? file.angle_si : file.length_si)};
  } catch (const std::invalid_argument& e) {
    bad("--lock " + name + ": " + e.what());
  }
}

// "crank=0,0,10": a velocity guess for one body (vx, vy[, ω]) in the file's length/time and
// angle/time units.
void parse_velocity(const Model& model, const std::string& text, VecX& u0) {
  const UnitSystem file = unit_system(model.units);
  const double scale[3] = {file.length_si / file.time_si, file.length_si / file.time_si,
                           file.angle_si / file.time_si};
  const auto eq = text.find('=');
  if (eq == std::string::npos) bad("--velocity expects BODY=vx,vy,omega, got '" + text + "'");
  const std::string name = text.substr(0, eq);
  const int b = model.find_body(name);
  if (b < 0) bad("--velocity: body '" + name + "' is not a moving body");
  const Body& body = model.bodies[static_cast<size_t>(b)];
  std::vector<double> v;
  std::stringstream ss(text.substr(eq + 1));
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || item.size() > kMaxNumberLength || end != item.c_str() + item.size())
      bad("--velocity " + name + ": '" + item + "' is not a number");
    const std::string problem = range_problem(x, Quantity::general);
    if (!problem.empty()) bad("--velocity " + name + ": '" + item + "': the value " + problem);
    v.push_back(x);
  }
  if (static_cast<int>(v.size()) != body.nu())
    bad("--velocity " + name + ": expected " + std::to_string(body.nu()) + " numbers");
  for (int k = 0; k < body.nu(); ++k) u0(body.u_offset + k) = v[static_cast<size_t>(k)] * scale[k];
}

int run_assemble(const AssembleOptions& opt) {
  const Model model = load(opt.file, opt.sets);
  const UnitSystem U = resolve_units(model, opt.units);
  const OutputUnit length_u = output_unit(Dimension::length, U);
  const OutputUnit angle_u = output_unit(Dimension::angle, U);
  const OutputUnit energy_u = output_unit(Dimension::moment, U);
  auto joint_unit = [&](int joint) {
    return std::holds_alternative<Revolute>(model.joints[static_cast<size_t>(joint)].kind)
               ? angle_u
               : length_u;
  };
  auto measure_unit = [&](const Measure& m) { return output_unit(dimension_of(m.unit), U); };
  AssemblyOptions options;
  options.tolerance = opt.tolerance;
  options.use_limits = !opt.no_limits;
  if (!opt.position.empty()) {
    const auto it = std::find_if(model.design_positions.begin(), model.design_positions.end(),
                                 [&](const DesignPosition& p) { return p.name == opt.position; });
    if (it == model.design_positions.end())
      bad("--position: design position '" + opt.position + "' is not defined");
    for (const auto& [joint, value] : it->inputs) options.locks.push_back({joint, value});
  }
  for (const std::string& l : opt.locks) options.locks.push_back(parse_lock(model, l));
  VecX u0 = VecX::Zero(model.n);
  for (const std::string& v : opt.velocities) parse_velocity(model, v, u0);

  namespace fs = std::filesystem;
  std::string write_to = opt.write;
  if (!opt.sets.empty() && (opt.in_place || !write_to.empty()))
    bad("--set cannot be combined with --write or --in-place: they write the file as it is on "
        "disk; change the file itself to keep a change");
  if (opt.in_place) {
    if (!write_to.empty()) bad("--in-place and --write are exclusive");
    write_to = opt.file;
  } else if (!write_to.empty()) {
    std::error_code ec;
    if (fs::exists(write_to, ec) && fs::equivalent(write_to, opt.file, ec))
      bad("--write would overwrite the input file '" + opt.file + "'; use --in-place for that");
  }

  const VecX q0 = model.design_q();
  const AssemblyResult res = assemble(model, q0, options);
  const bool ok =
      res.status == AssemblyStatus::assembled || res.status == AssemblyStatus::unchanged;
  VelocityProjection vel;
  if (ok) vel = project_velocities(model, res.q, u0);
  // A limit that keeps it from closing: the value the joint would need.
  const std::vector<LimitBlock> blocks =
      ok ? std::vector<LimitBlock>{} : find_limit_blocks(model, q0, options);

  std::string written;
  if (ok && !write_to.empty()) {
    std::ifstream in(opt.file, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    // The edited text is checked to re-read as the assembled mechanism before anything is
    // written; a file that cannot be edited so is an InputError (exit 2, printed once by main).
    const std::string edited = replace_design_poses(text.str(), opt.file, model, res.q);
    try {
      write_file_atomically(write_to, edited);
    } catch (const std::runtime_error& e) {  // e.g. no such directory, no permission
      spdlog::error("{}", e.what());
      return kBadInput;
    }
    written = write_to;
    spdlog::info("wrote {}", written);
  }

  std::ostringstream out;
  if (opt.json) {
    nlohmann::json j;
    j["mechanism"] = model.name;
    j["file"] = model.file;
    j["units"] = units_json(U);
    j["status"] = to_string(res.status);
    j["message"] = res.message;
    j["solver_status"] = res.solver_status;
    j["iterations"] = res.iterations;
    j["residual"] = res.residual;
    j["distance"] = res.distance;
    nlohmann::json locks = nlohmann::json::array();
    for (const JointLock& l : options.locks)
      locks.push_back({{"joint", model.joints[static_cast<size_t>(l.joint)].name},
                       {"value", joint_unit(l.joint).from_si(l.value)},
                       {"unit", joint_unit(l.joint).name}});
    j["locks"] = locks;
    nlohmann::json bodies = nlohmann::json::array();
    for (const BodyMove& b : res.bodies)
      bodies.push_back({{"name", b.body},
                        {"translation", length_u.from_si(b.translation)},
                        {"rotation", angle_u.from_si(b.rotation)}});
    j["bodies"] = bodies;
    auto joints_json = [&](const std::vector<JointResidual>& list) {
      nlohmann::json a = nlohmann::json::array();
      for (const JointResidual& r : list) {
        const int ji = model.find_joint(r.joint);
        const auto names = model.joints[static_cast<size_t>(ji)].component_names();
        nlohmann::json rows;
        for (size_t k = 0; k < r.rows.size(); ++k) rows[names[k]] = r.rows[k];
        a.push_back({{"name", r.joint},
                     {"residual", r.residual},
                     {"gap", length_u.from_si(r.gap)},
                     {"rows", rows}});
      }
      return a;
    };
    j["joints"] = joints_json(res.joints);
    nlohmann::json measures = nlohmann::json::object();
    if (ok)
      for (const Measure& m : model.measures)
        measures[m.name] = m.derivative < 2
                               ? nlohmann::json(measure_unit(m).from_si(
                                     evaluate_measure(model, m, res.q, &vel.u, nullptr)))
                               : nlohmann::json(nullptr);
    j["measures"] = measures;
    j["q"] = std::vector<double>(res.q.data(), res.q.data() + res.q.size());
    if (ok)
      j["velocities"] = {{"u", std::vector<double>(vel.u.data(), vel.u.data() + vel.u.size())},
                         {"kinetic_initial", energy_u.from_si(vel.kinetic_initial)},
                         {"kinetic", energy_u.from_si(vel.kinetic)},
                         {"kinetic_removed", energy_u.from_si(vel.kinetic_removed)}};
    nlohmann::json lb = nlohmann::json::array();
    for (const LimitBlock& b : blocks) {
      const Joint& jt = model.joints[static_cast<size_t>(b.joint)];
      const OutputUnit u = joint_unit(b.joint);
      lb.push_back({{"joint", jt.name},
                    {"needed", u.from_si(b.needed)},
                    {"limits", {u.from_si(jt.limits->x()), u.from_si(jt.limits->y())}},
                    {"unit", u.name}});
    }
    j["limit_blocks"] = lb;
    j["gaps"] = joints_json(res.gaps);
    j["total_gap"] = res.total_gap;
    j["written"] = written.empty() ? nlohmann::json(nullptr) : nlohmann::json(written);
    out << j.dump(2) << '\n';
  } else {
    out << "mechanism   " << model.name << "  (" << model.file << ")\n";
    out << "status      " << to_string(res.status) << "\n";
    out << "            " << res.message << "\n";
    if (!res.solver_status.empty())
      out << "solver      Ipopt " << res.solver_status << ", " << res.iterations
          << " iterations (Ipopt + Newton polish)\n";
    for (const LimitBlock& b : blocks) {
      const Joint& jt = model.joints[static_cast<size_t>(b.joint)];
      const bool rev = std::holds_alternative<Revolute>(jt.kind);
      out << "limit       joint '" << jt.name << "' would need " << format_input(b.needed, rev, U)
          << ", outside its limits [" << format_input(jt.limits->x(), rev, U) << ", "
          << format_input(jt.limits->y(), rev, U) << "]\n";
    }
    out << "residual    " << fmt(res.residual, 3) << "   (max |f|, locks, limits; m or rad)\n";
    out << "distance    " << fmt(res.distance, 4) << "   (mass metric, sqrt(kg)*m)\n";
    for (const JointLock& l : options.locks)
      out << "lock        " << model.joints[static_cast<size_t>(l.joint)].name << " = "
          << fmt(joint_unit(l.joint).from_si(l.value), 10) << " " << joint_unit(l.joint).name
          << "\n";
    out << "\nbody          moved [" << length_u.name << "]   turned [" << angle_u.name << "]\n";
    for (const BodyMove& b : res.bodies) {
      char line[160];
      std::snprintf(line, sizeof line, "  %-12s %10.4f %12.5f\n", b.body.c_str(),
                    length_u.from_si(b.translation), angle_u.from_si(b.rotation));
      out << line;
    }
    out << "\njoint         residual\n";
    for (const JointResidual& r : res.joints) {
      char line[160];
      std::snprintf(line, sizeof line, "  %-12s %10.3g\n", r.joint.c_str(), r.residual);
      out << line;
    }
    if (ok) {
      if (!model.measures.empty()) out << "\nmeasure       value\n";
      for (const Measure& m : model.measures) {
        if (m.derivative > 1) continue;
        out << "  " << m.name << "  "
            << fmt(measure_unit(m).from_si(evaluate_measure(model, m, res.q, &vel.u, nullptr)), 10)
            << " " << measure_unit(m).name << "\n";
      }
      out << "\nvelocities  u = alpha u0: kinetic energy "
          << fmt(energy_u.from_si(vel.kinetic_initial)) << " " << energy_u.name << " -> "
          << fmt(energy_u.from_si(vel.kinetic)) << " " << energy_u.name << " (removed "
          << fmt(energy_u.from_si(vel.kinetic_removed)) << " " << energy_u.name << ")\n";
    }
    if (!written.empty()) out << "\nwritten     " << written << "\n";
  }
  std::cout << out.str();
  if (!ok) {
    spdlog::error("{}: {}", model.file, res.message);
    for (const LimitBlock& b : blocks) {
      const Joint& jt = model.joints[static_cast<size_t>(b.joint)];
      const bool rev = std::holds_alternative<Revolute>(jt.kind);
      spdlog::error("{}: joint '{}' would need {}, outside its limits [{}, {}]", model.file,
                    jt.name, format_input(b.needed, rev, U), format_input(jt.limits->x(), rev, U),
                    format_input(jt.limits->y(), rev, U));
    }
    return kNumerical;
  }
  return kOk;
}

}  // namespace

void register_assemble(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<AssembleOptions>();
  CLI::App* cmd = app.add_subcommand(
      "assemble",
      "project the design position onto the constraints (Ipopt, mass metric), with locked "
      "inputs and joint limits; initial velocities u = alpha u0");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  add_set_option(cmd, opt->sets);
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  cmd->add_option("--lock", opt->locks,
                  "JOINT=VALUE: lock a revolute/prismatic joint (30deg, 12mm; a bare number is in "
                  "the file's declared units); repeatable");
  cmd->add_option("--position", opt->position,
                  "lock the inputs of this design position of the file");
  cmd->add_flag("--no-limits", opt->no_limits, "ignore the joint limits of the file");
  cmd->add_option("--velocity", opt->velocities,
                  "BODY=vx,vy,omega: initial velocity guess u0 of a body, in the file's declared "
                  "units (length/time, angle/time); repeatable");
  cmd->add_option("--write", opt->write,
                  "save a mechanism file whose design position is the assembled one");
  cmd->add_flag("--in-place", opt->in_place, "overwrite the input file with the assembled one");
  cmd->add_option("--tolerance", opt->tolerance, "max residual of an assembled position (m, rad)")
      ->check(finite_range(0.0, 1.0, true));
  add_units_option(cmd, opt->units);
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    setup_logging(globals, *log);
    exit_code = run_assemble(*opt);
  });
}

}  // namespace orthomech::cli

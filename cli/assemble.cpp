// `orthomech assemble FILE`: projects the design position onto the constraint manifold (Ipopt,
// analysis/assembly.hpp), reports how far each body moved, the joint residuals, the solver
// status, the measures at the assembled position and the initial velocities u = α u₀; with
// --write saves a mechanism file whose design position is the assembled one (docs/cli.md).
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
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
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/mechanism_writer.hpp"
#include "orthomech/io/noise.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "run_bounds.hpp"

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
  double time_limit = 0.0;  // --time-limit (s of wall clock; 0: none)
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
  if (j < 0) {  // a measure's value: its position quantity, in its unit (rad: an angle)
    const int m = model.find_measure(name);
    if (m < 0) bad("--lock: joint '" + name + "' is not defined, nor a measure of that name");
    const Measure& measure = model.measures[static_cast<size_t>(m)];
    const bool angular = measure.unit.rfind("rad", 0) == 0;
    const UnitSystem file = unit_system(model.units);
    try {
      JointLock l;
      l.value =
          parse_position(text.substr(eq + 1), angular, angular ? file.angle_si : file.length_si);
      l.measure = m;
      return l;
    } catch (const std::invalid_argument& e) {
      bad("--lock " + name + ": " + e.what());
    }
  }
  const CoordinateKind kind = joint_coordinate_kind(model.joints[static_cast<size_t>(j)]);
  if (kind == CoordinateKind::none)
    bad("--lock: joint '" + name + "' has no coordinate (" +
        (model.dimension == 3 ? "revolute, cylindrical and screw joints have an angle, prismatic "
                                "joints a slide"
                              : "it is neither revolute nor prismatic") +
        ")");
  const bool angular = kind == CoordinateKind::angle;
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
  const OutputUnit distance_u = mass_metric_unit(U);
  auto joint_unit = [&](int joint) {
    return joint_coordinate_kind(model.joints[static_cast<size_t>(joint)]) == CoordinateKind::angle
               ? angle_u
               : length_u;
  };
  // A lock's name and output unit: its joint's, or its measure's.
  auto lock_name = [&](const JointLock& l) {
    return l.measure >= 0 ? model.measures[static_cast<size_t>(l.measure)].name
                          : model.joints[static_cast<size_t>(l.joint)].name;
  };
  auto lock_unit = [&](const JointLock& l) {
    if (l.measure < 0) return joint_unit(l.joint);
    return model.measures[static_cast<size_t>(l.measure)].unit.rfind("rad", 0) == 0 ? angle_u
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
  // Bounded (run_bounds.hpp): --time-limit, SIGINT/SIGTERM, a progress line on a terminal.
  options.control = run_control("assemble", opt.time_limit);
  const AssemblyResult res = run_bounded([&] { return assemble(model, q0, options); });
  const bool ok =
      res.status == AssemblyStatus::assembled || res.status == AssemblyStatus::unchanged;
  VelocityProjection vel;
  if (ok) vel = project_velocities(model, res.q, u0);
  // A limit that keeps it from closing: the value the joint would need.
  // (find_limit_blocks follows joint locks only.)
  const bool measure_locks = std::any_of(options.locks.begin(), options.locks.end(),
                                         [](const JointLock& l) { return l.measure >= 0; });
  const std::vector<LimitBlock> blocks =
      ok || measure_locks ? std::vector<LimitBlock>{} : find_limit_blocks(model, q0, options);

  std::string written;
  if (ok && !write_to.empty()) {
    std::ifstream in(opt.file, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    // The edited text is checked to re-read as the assembled mechanism before anything is
    // written; a file that cannot be edited so is an InputError (exit 2, printed once by main).
    const PoseEdit edited = edit_design_poses(text.str(), opt.file, model, res.q);
    for (const std::string& note : edited.replaced_expressions)
      spdlog::warn("{}: {}", opt.file, note);
    try {
      write_file(write_to, edited.text);
    } catch (const std::runtime_error& e) {  // e.g. no such directory, no permission
      spdlog::error("{}", e.what());
      return kBadInput;
    }
    written = write_to;
    spdlog::info("wrote {}", written);
  }

  // How far the bodies moved, rounding noise as 0 (a crank turning about its frame's origin):
  // against the largest coordinate of the mechanism (io/noise.hpp).
  NoiseFloor noise;
  for (const Body& b : model.bodies)
    for (int k = 0; k < 2; ++k) {
      noise.see(Dimension::length, q0(b.q_offset + k));
      noise.see(Dimension::length, res.q(b.q_offset + k));
    }
  auto moved = [&](double v) { return length_u.from_si(noise.clean(Dimension::length, v)); };
  auto turned = [&](double v) { return angle_u.from_si(noise.clean(Dimension::angle, v)); };
  std::ostringstream out;
  if (opt.json) {
    nlohmann::json j;
    j["mechanism"] = model.name;
    j["file"] = model.file;
    j["units"] = units_json(U);
    j["status"] = to_string(res.status);
    j["complete"] = res.status != AssemblyStatus::stopped;
    if (res.status == AssemblyStatus::stopped) j["stop"] = to_string(res.stop);
    j["message"] = res.message;
    j["solver_status"] = res.solver_status;
    j["iterations"] = res.iterations;
    j["residual_length"] = length_u.from_si(res.residual_length);
    j["residual_angle"] = angle_u.from_si(res.residual_angle);
    j["distance"] = distance_u.from_si(res.distance);
    j["distance_unit"] = distance_u.name;
    nlohmann::json locks = nlohmann::json::array();
    for (const JointLock& l : options.locks)
      locks.push_back({{l.measure >= 0 ? "measure" : "joint", lock_name(l)},
                       {"value", lock_unit(l).from_si(l.value)},
                       {"unit", lock_unit(l).name}});
    j["locks"] = locks;
    nlohmann::json bodies = nlohmann::json::array();
    for (const BodyMove& b : res.bodies)
      bodies.push_back({{"name", b.body},
                        {"translation", moved(b.translation)},
                        {"rotation", turned(b.rotation)}});
    j["bodies"] = bodies;
    auto joints_json = [&](const std::vector<JointResidual>& list) {
      nlohmann::json a = nlohmann::json::array();
      for (const JointResidual& r : list) {
        const int ji = model.find_joint(r.joint);
        const auto names = model.joints[static_cast<size_t>(ji)].component_names();
        nlohmann::json rows;
        double max_length = 0.0, max_angle = 0.0;  // output units
        for (size_t k = 0; k < r.rows.size(); ++k) {
          const bool angular = is_angular_row(names[k]);
          const double v = (angular ? angle_u : length_u).from_si(r.rows[k]);
          rows[names[k]] = v;
          double& to = angular ? max_angle : max_length;
          to = std::max(to, std::abs(v));
        }
        a.push_back({{"name", r.joint},
                     {"residual_length", max_length},
                     {"residual_angle", max_angle},
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
    j["q"] = coordinates_out(model, res.q, U);
    // Spatial: each body frame, its origin and orientation (what --write writes).
    if (model.dimension == 3) {
      nlohmann::json poses = nlohmann::json::array();
      for (const Body& b : model.bodies) {
        const Quat e = res.q.segment<4>(b.q_offset + 3) / res.q.segment<4>(b.q_offset + 3).norm();
        const Vec3 r = res.q.segment<3>(b.q_offset) - rotation_matrix(e) * b.spatial.com_local;
        poses.push_back(
            {{"name", b.name},
             {"position",
              {length_u.from_si(r.x()), length_u.from_si(r.y()), length_u.from_si(r.z())}},
             {"orientation", {e(0), e(1), e(2), e(3)}}});
      }
      j["poses"] = poses;
    }
    if (ok)
      j["velocities"] = {{"u", coordinates_out(model, vel.u, U, true)},
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
    j["total_gap"] = length_u.from_si(res.total_gap);
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
      const bool rev = b.angular;
      out << "limit       joint '" << jt.name << "' would need " << format_input(b.needed, rev, U)
          << ", outside its limits [" << format_input(jt.limits->x(), rev, U) << ", "
          << format_input(jt.limits->y(), rev, U) << "]\n";
    }
    out << "residual    " << fmt(length_u.from_si(res.residual_length), 3) << " " << length_u.name
        << ", " << fmt(angle_u.from_si(res.residual_angle), 3) << " " << angle_u.name
        << "   (max |f|, locks, limits: length rows, angle rows)\n";
    out << "distance    " << fmt(distance_u.from_si(res.distance), 4) << " " << distance_u.name
        << "   (mass metric)\n";
    for (const JointLock& l : options.locks)
      out << "lock        " << lock_name(l) << " = " << fmt(lock_unit(l).from_si(l.value), 10)
          << " " << lock_unit(l).name << "\n";
    // Columns as wide as their longest entry (body, joint and measure names, headers).
    auto width_of = [](const std::string& header, const auto& names) {
      size_t w = header.size();
      for (const std::string& n : names) w = std::max(w, n.size());
      return static_cast<int>(w);
    };
    std::vector<std::string> body_names, joint_names, measure_names;
    for (const BodyMove& b : res.bodies) body_names.push_back(b.body);
    for (const JointResidual& r : res.joints) joint_names.push_back(r.joint);
    for (const Measure& m : model.measures)
      if (m.derivative <= 1) measure_names.push_back(m.name);
    auto pad = [](const std::string& text, int width) {
      return text +
             std::string(static_cast<size_t>(std::max(0, width - static_cast<int>(text.size()))),
                         ' ');
    };
    char line[96];
    {
      const int w = width_of("body", body_names);
      const std::string moved_head = "moved [" + length_u.name + "]";
      const std::string turned_head = "turned [" + angle_u.name + "]";
      const int wm = std::max(14, static_cast<int>(moved_head.size()));
      out << "\n  " << pad("body", w) << "  " << pad(moved_head, wm) << "  " << turned_head << "\n";
      for (const BodyMove& b : res.bodies) {
        std::snprintf(line, sizeof line, "%.6g", moved(b.translation));
        out << "  " << pad(b.body, w) << "  " << pad(line, wm) << "  " << fmt(turned(b.rotation))
            << "\n";
      }
    }
    {
      const int w = width_of("joint", joint_names);
      const std::string lh = "residual [" + length_u.name + "]";
      const std::string ah = "residual [" + angle_u.name + "]";
      const int wl = std::max(14, static_cast<int>(lh.size()));
      out << "\n  " << pad("joint", w) << "  " << pad(lh, wl) << "  " << ah << "\n";
      for (const JointResidual& r : res.joints) {
        const auto names =
            model.joints[static_cast<size_t>(model.find_joint(r.joint))].component_names();
        double max_length = 0.0, max_angle = 0.0;
        bool has_length = false, has_angle = false;
        for (size_t k = 0; k < r.rows.size(); ++k) {
          const bool angular = is_angular_row(names[k]);
          (angular ? has_angle : has_length) = true;
          double& to = angular ? max_angle : max_length;
          to = std::max(to, std::abs((angular ? angle_u : length_u).from_si(r.rows[k])));
        }
        char lv[32] = "-", av[32] = "-";
        if (has_length) std::snprintf(lv, sizeof lv, "%.3g", max_length);
        if (has_angle) std::snprintf(av, sizeof av, "%.3g", max_angle);
        out << "  " << pad(r.joint, w) << "  " << pad(lv, wl) << "  " << av << "\n";
      }
    }
    if (ok) {
      const int w = width_of("measure", measure_names);
      if (!measure_names.empty()) out << "\n  " << pad("measure", w) << "  value\n";
      for (const Measure& m : model.measures) {
        if (m.derivative > 1) continue;
        const OutputUnit u = measure_unit(m);
        const double v = u.from_si(evaluate_measure(model, m, res.q, &vel.u, nullptr));
        out << "  " << pad(m.name, w) << "  " << fmt(v, 10) << " " << u.name << "\n";
      }
      out << "\nvelocities  u = alpha u0: kinetic energy "
          << fmt(energy_u.from_si(vel.kinetic_initial)) << " " << energy_u.name << " -> "
          << fmt(energy_u.from_si(vel.kinetic)) << " " << energy_u.name << " (removed "
          << fmt(energy_u.from_si(vel.kinetic_removed)) << " " << energy_u.name << ")\n";
    }
    if (!written.empty()) out << "\nwritten     " << written << "\n";
  }
  std::cout << out.str();
  if (res.status == AssemblyStatus::stopped) {  // nothing written: not assembled
    spdlog::error("assemble: stopped: {}", res.message);
    return kStopped;
  }
  if (!ok) {
    spdlog::error("{}: {}", model.file, res.message);
    for (const LimitBlock& b : blocks) {
      const Joint& jt = model.joints[static_cast<size_t>(b.joint)];
      const bool rev = b.angular;
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
                  "JOINT=VALUE: lock a joint's coordinate (30deg, 12mm; a bare number is in the "
                  "file's declared units), or MEASURE=VALUE a measure's value; repeatable");
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
  cmd->add_option("--time-limit", opt->time_limit,
                  "wall-clock limit in seconds (default: none): the projection stops there with "
                  "status stopped, nothing written, exit 5")
      ->check(finite_range(0.0, 1e9, true));
  add_units_option(cmd, opt->units);
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    setup_logging(globals, *log);
    exit_code = run_assemble(*opt);
  });
}

}  // namespace orthomech::cli

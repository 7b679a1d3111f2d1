// `orthomech info FILE [--json]`: structure and mobility of a mechanism (docs/design.md §8).
// The design position is first projected onto f(q) = 0 (mass-metric Gauss–Newton), because the
// rank of E, and so the redundancy, is a property of the constraint manifold.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech::cli {

namespace {

struct InfoOptions {
  std::string file;
  std::vector<std::string> sets;  // --set PATH=VALUE
  bool json = false;
  std::string units = "file";
};

std::string fmt_double(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

int run_info(const InfoOptions& opt) {
  const Model model = load(opt.file, opt.sets);
  VecX q = model.design_q();
  const VecX q_design = q;
  const SolveResult assembly = project_positions(model, q);
  // How far the projection moved the bodies and what is left of f, in the output units: lengths
  // (translation, length rows of f) and angles (rotation, angular rows).
  const UnitSystem U = resolve_units(model, opt.units);
  const OutputUnit length_u = output_unit(Dimension::length, U);
  const OutputUnit angle_u = output_unit(Dimension::angle, U);
  const ResidualSplit residual = split_residual(model, q);
  auto residual_text = [&] {
    return fmt_double(length_u.from_si(residual.length)) + " " + length_u.name + ", " +
           fmt_double(angle_u.from_si(residual.angle)) + " " + angle_u.name;
  };
  if (assembly.status != SolveStatus::converged) {
    spdlog::warn(
        "{}: the design position does not assemble ({}; residual {}); "
        "mobility is reported at the design position as given",
        model.file, to_string(assembly.status), residual_text());
    q = q_design;
  }
  const Mobility mob = compute_mobility(model, q);
  const OutputUnit mass_u = output_unit(Dimension::mass, U);
  const OutputUnit inertia_u = output_unit(Dimension::inertia, U);
  double moved_length = 0.0, moved_angle = 0.0;
  for (const Body& b : model.bodies) {
    if (b.kind == BodyKind::spatial) {  // |Δr| and the rotation angle of e₀* ⊗ e
      moved_length = std::max(moved_length,
                              (q.segment<3>(b.q_offset) - q_design.segment<3>(b.q_offset)).norm());
      Quat e0 = q_design.segment<4>(b.q_offset + 3);
      e0.tail<3>() = -e0.tail<3>();
      const Quat d = quaternion_multiply(e0, q.segment<4>(b.q_offset + 3));
      moved_angle = std::max(moved_angle, 2.0 * std::atan2(d.tail<3>().norm(), std::abs(d(0))));
      continue;
    }
    moved_length =
        std::max(moved_length, (q.segment<2>(b.q_offset) - q_design.segment<2>(b.q_offset)).norm());
    if (b.kind == BodyKind::rigid)
      moved_angle = std::max(moved_angle, std::abs(q(b.q_offset + 2) - q_design(b.q_offset + 2)));
  }

  std::ostringstream out;
  if (opt.json) {
    nlohmann::json j;
    j["mechanism"] = model.name;
    j["file"] = model.file;
    j["units"] = units_json(U);
    j["coordinates"] = mob.nq;
    j["velocities"] = mob.n;
    j["constraints"] = mob.nc;
    j["rank"] = mob.rank;
    j["dof"] = mob.dof;
    j["grubler"] = mob.grubler;
    j["redundant"] = mob.redundant;
    if (!mob.idle.empty()) {  // idle degrees of freedom (counted in dof); absent when none
      nlohmann::json idle = nlohmann::json::array();
      for (const Mobility::Idle& i : mob.idle)
        idle.push_back({{"body", i.body}, {"count", i.count}});
      j["idle"] = idle;
    }
    j["rank_tolerance"] = mob.tolerance;
    j["smallest_pivot"] = mob.smallest_pivot;
    j["assembly"] = {{"status", to_string(assembly.status)},
                     {"iterations", assembly.iterations},
                     {"residual_length", length_u.from_si(residual.length)},
                     {"residual_angle", angle_u.from_si(residual.angle)},
                     {"max_translation", length_u.from_si(moved_length)},
                     {"max_rotation", angle_u.from_si(moved_angle)}};
    nlohmann::json bodies = nlohmann::json::array();
    for (const Body& b : model.bodies) {
      if (b.kind == BodyKind::spatial) {  // the inertia tensor about the com, body axes (rows)
        nlohmann::json J = nlohmann::json::array();
        for (int r = 0; r < 3; ++r)
          J.push_back({inertia_u.from_si(b.spatial.inertia(r, 0)),
                       inertia_u.from_si(b.spatial.inertia(r, 1)),
                       inertia_u.from_si(b.spatial.inertia(r, 2))});
        bodies.push_back({{"name", b.name},
                          {"type", "spatial"},
                          {"mass", mass_u.from_si(b.mass)},
                          {"inertia", J}});
        continue;
      }
      bodies.push_back({{"name", b.name},
                        {"type", b.kind == BodyKind::rigid ? "rigid" : "particle"},
                        {"mass", mass_u.from_si(b.mass)},
                        {"inertia", inertia_u.from_si(b.inertia)}});
    }
    if (model.dimension == 3) j["dimension"] = 3;  // planar output unchanged
    j["bodies"] = bodies;
    nlohmann::json joints = nlohmann::json::array();
    for (const Joint& jt : model.joints)
      joints.push_back(
          {{"name", jt.name}, {"type", jt.type_name()}, {"equations", jt.component_names()}});
    j["joints"] = joints;
    nlohmann::json measures = nlohmann::json::array();
    for (const Measure& m : model.measures)
      measures.push_back({{"name", m.name}, {"unit", output_unit(dimension_of(m.unit), U).name}});
    j["measures"] = measures;
    out << j.dump(2) << '\n';
  } else {
    out << "mechanism     " << model.name << "  (" << model.file << ")\n";
    out << "bodies        " << model.bodies.size() << " moving + ground\n";
    out << "coordinates   nq = " << mob.nq << ", n = " << mob.n << "\n";
    out << "constraints   n_c = " << mob.nc << " in " << model.joints.size() << " joints\n";
    out << "rank of E     " << mob.rank << "   (smallest kept pivot "
        << fmt_double(mob.smallest_pivot) << ", tolerance " << fmt_double(mob.tolerance) << ")\n";
    out << "DOF           " << mob.dof << "   (Grübler–Kutzbach count " << mob.grubler << ")\n";
    out << "redundant     ";
    if (mob.redundant.empty()) out << "none";
    for (size_t k = 0; k < mob.redundant.size(); ++k) out << (k ? "; " : "") << mob.redundant[k];
    out << "\n";
    for (const Mobility::Idle& i : mob.idle)
      out << "idle          body '" << i.body << "' can move alone (" << i.count
          << (i.count == 1 ? " direction" : " directions") << ", counted in the DOF)\n";
    out << "design pose   " << to_string(assembly.status) << " onto f(q) = 0 in "
        << assembly.iterations << " iterations, bodies moved up to "
        << fmt_double(length_u.from_si(moved_length)) << " " << length_u.name
        << " and turned up to " << fmt_double(angle_u.from_si(moved_angle)) << " " << angle_u.name
        << ", residual " << residual_text() << "\n\n";
    out << "joints\n";
    for (const Joint& jt : model.joints) {
      out << "  " << jt.name << "  " << jt.type_name() << "  (";
      const auto comps = jt.component_names();
      for (size_t k = 0; k < comps.size(); ++k) out << (k ? ", " : "") << comps[k];
      out << ")\n";
    }
    if (!model.measures.empty()) {
      out << "measures\n";
      for (const Measure& m : model.measures)
        out << "  " << m.name << " [" << output_unit(dimension_of(m.unit), U).name << "]\n";
    }
  }
  std::cout << out.str();  // all at once: no partial output on failure
  return kOk;
}

}  // namespace

void register_info(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<InfoOptions>();
  CLI::App* cmd =
      app.add_subcommand("info",
                         "bodies, joints, coordinates, constraints, rank of E, DOF, Grübler count, "
                         "redundant equations");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  add_set_option(cmd, opt->sets);
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  add_units_option(cmd, opt->units);
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    setup_logging(globals, *log);
    exit_code = run_info(*opt);
  });
}

}  // namespace orthomech::cli

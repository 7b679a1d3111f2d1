#include "cycle_drivers.hpp"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common.hpp"
#include "orthomech/analysis/multi_drive.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/cycle_output.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/json_stream.hpp"
#include "orthomech/io/number_text.hpp"
#include "orthomech/io/units.hpp"

namespace orthomech::cli {

namespace {

// The file's drivers named on the command line (a driver's name or its joint's).
std::vector<Driver> resolve_drivers(const Model& model, const std::vector<std::string>& names) {
  std::vector<Driver> out;
  for (const std::string& name : names) {
    const Driver* found = nullptr;
    for (const Driver& d : model.drivers)
      if (d.name == name ||
          (d.joint >= 0 && model.joints[static_cast<size_t>(d.joint)].name == name))
        found = &d;
    if (!found) {
      std::string known;
      for (const Driver& d : model.drivers) known += (known.empty() ? "" : ", ") + d.name;
      throw CLI::ValidationError("--drivers", "'" + name + "' is not a driver of " + model.file +
                                                  " (drivers: " + known + ")");
    }
    out.push_back(*found);
  }
  return out;
}

// Per component series: max, min (signed) and RMS over the positions.
struct Series {
  std::string name;
  Dimension dimension;
  double max = -INFINITY, min = INFINITY, t_max = 0.0, t_min = 0.0, sum2 = 0.0;
  int count = 0;
  void see(double t, double v) {
    if (v > max) max = v, t_max = t;
    if (v < min) min = v, t_min = t;
    sum2 += v * v;
    ++count;
  }
};

}  // namespace

int run_cycle_drivers(const Model& model, const DriversRequest& request) {
  warn_friction_not_applied(model, "cycle --drivers");
  const UnitSystem U = resolve_units(model, request.units);
  MultiDriveOptions mo;
  mo.drivers = resolve_drivers(model, request.drivers);
  mo.t_end = request.t_end;
  if (request.steps > 0) mo.steps = request.steps;
  const MultiDriveResult r = run_multi_drive(model, mo);
  if (r.status == MultiDriveStatus::invalid_request)
    throw CLI::ValidationError("--drivers", r.message);
  if (r.points.empty()) {
    spdlog::error("{}: the sweep cannot start: {}", model.file, r.message);
    return kNumerical;
  }
  if (r.status != MultiDriveStatus::completed) spdlog::warn("{}: {}", model.file, r.message);
  for (const std::string& w : r.warnings) spdlog::warn("{}: {}", model.file, w);

  // Units and series: each driver's input and force, each reaction component and magnitude.
  const OutputUnit time_u = output_unit(Dimension::time, U);
  std::vector<Dimension> input_dim, drive_dim;
  for (const Driver& d : mo.drivers) {
    const bool angular =
        joint_coordinate_kind(model.joints[static_cast<size_t>(d.joint)]) == CoordinateKind::angle;
    input_dim.push_back(angular ? Dimension::angle : Dimension::length);
    drive_dim.push_back(angular ? Dimension::moment : Dimension::force);
  }
  std::vector<Series> series;
  for (size_t i = 0; i < mo.drivers.size(); ++i)
    series.push_back({"drive." + mo.drivers[i].name, drive_dim[i]});
  for (const ReactionComponent& c : r.components) series.push_back({c.name, dimension_of(c.unit)});
  for (const MultiDrivenPoint& p : r.points) {
    size_t k = 0;
    for (Eigen::Index i = 0; i < p.drives.size(); ++i) series[k++].see(p.time, p.drives(i));
    for (const double v : p.reactions) series[k++].see(p.time, v);
  }
  auto value = [&](Dimension d, double v) { return output_unit(d, U).from_si(v); };

  if (!request.out.empty()) {
    std::filesystem::create_directories(request.out);
    std::ostringstream csv;
    csv << "time [" << time_u.name << "]";
    for (size_t i = 0; i < mo.drivers.size(); ++i)
      csv << ",input." << mo.drivers[i].name << " [" << output_unit(input_dim[i], U).name << "]";
    for (const Measure& m : model.measures)
      csv << "," << m.name << " [" << output_unit(dimension_of(m.unit), U).name << "]";
    for (const Series& s : series)
      csv << "," << s.name << " [" << output_unit(s.dimension, U).name << "]";
    csv << "\n";
    std::string line;  // one row's text: printf's "%.12g" per number, without printf
    const auto cell = [&](Dimension d, double v) {
      line += ',';
      append_number(line, value(d, v), kCsvDigits);
    };
    for (const MultiDrivenPoint& p : r.points) {
      line.clear();
      append_number(line, time_u.from_si(p.time), kCsvDigits);
      for (Eigen::Index i = 0; i < p.inputs.size(); ++i)
        cell(input_dim[static_cast<size_t>(i)], p.inputs(i));
      for (size_t i = 0; i < model.measures.size(); ++i)
        cell(dimension_of(model.measures[i].unit), p.measures[i]);
      for (Eigen::Index i = 0; i < p.drives.size(); ++i)
        cell(drive_dim[static_cast<size_t>(i)], p.drives(i));
      for (size_t i = 0; i < p.reactions.size(); ++i)
        cell(dimension_of(r.components[i].unit), p.reactions[i]);
      line += '\n';
      csv << line;
    }
    const std::filesystem::path file = std::filesystem::path(request.out) / "drivers.csv";
    write_file(file, csv.str());
    spdlog::info("wrote {} ({} positions)", file.string(), r.points.size());
  }

  if (request.json) {
    nlohmann::json j;
    j["mechanism"] = model.name;
    j["file"] = model.file;
    j["status"] = to_string(r.status);
    j["message"] = r.message;
    j["dof"] = r.dof;
    j["rank"] = r.rank;
    j["redundant"] = r.redundant;
    j["t_end"] = time_u.from_si(r.t_end);
    nlohmann::json drivers = nlohmann::json::array();
    for (size_t i = 0; i < mo.drivers.size(); ++i)
      drivers.push_back({{"name", mo.drivers[i].name},
                         {"joint", model.joints[static_cast<size_t>(mo.drivers[i].joint)].name},
                         {"input_unit", output_unit(input_dim[i], U).name},
                         {"unit", output_unit(drive_dim[i], U).name}});
    j["drivers"] = drivers;
    nlohmann::json comps = nlohmann::json::array();
    for (size_t i = 0; i < r.components.size(); ++i)
      comps.push_back({{"name", r.components[i].name},
                       {"unit", output_unit(dimension_of(r.components[i].unit), U).name},
                       {"determinate", bool(r.determinate[i])}});
    j["components"] = comps;
    // The points one at a time (io/json_stream.hpp): 1e5 positions were a tree of 1 GB.
    const auto point_json = [&](size_t k) {
      const MultiDrivenPoint& p = r.points[k];
      nlohmann::json pj;
      pj["time"] = time_u.from_si(p.time);
      nlohmann::json in = nlohmann::json::object(), dr = nlohmann::json::object();
      for (size_t i = 0; i < mo.drivers.size(); ++i) {
        in[mo.drivers[i].name] = value(input_dim[i], p.inputs(static_cast<Eigen::Index>(i)));
        dr[mo.drivers[i].name] = value(drive_dim[i], p.drives(static_cast<Eigen::Index>(i)));
      }
      pj["inputs"] = in;
      pj["drives"] = dr;
      nlohmann::json ms = nlohmann::json::object(), rc = nlohmann::json::object();
      for (size_t i = 0; i < model.measures.size(); ++i)
        ms[model.measures[i].name] = value(dimension_of(model.measures[i].unit), p.measures[i]);
      for (size_t i = 0; i < r.components.size(); ++i)
        rc[r.components[i].name] = value(dimension_of(r.components[i].unit), p.reactions[i]);
      pj["measures"] = ms;
      pj["reactions"] = rc;
      pj["conditioning"] = p.conditioning;
      return pj;
    };
    j["points"] = kJsonStreamPlaceholder;
    write_json_streaming_array(std::cout, j.dump(2), r.points.size(),
                               [&](size_t k) { return point_json(k).dump(2); });
    std::cout << "\n";
  } else {
    std::ostringstream out;
    out << "mechanism       " << model.name << "  (" << model.file << ")\n";
    out << "drivers         ";
    for (size_t i = 0; i < mo.drivers.size(); ++i)
      out << (i ? ", " : "") << mo.drivers[i].name << " (joint '"
          << model.joints[static_cast<size_t>(mo.drivers[i].joint)].name << "')";
    out << "\nsweep           " << r.points.size() << " positions, t = 0 -> "
        << time_u.from_si(r.t_end) << " " << time_u.name << "\n";
    out << "status          " << to_string(r.status) << (r.message.empty() ? "" : ": ") << r.message
        << "\n";
    out << "mobility        DOF " << r.dof << ", rank of E " << r.rank << ", " << r.redundant
        << " redundant equation(s)\n\n";
    // The table: columns sized to the longest name; rounding noise of a component as 0 (below
    // 1e-12 of the largest of its dimension).
    size_t name_w = 8, unit_w = 4;
    for (const Series& s : series) {
      name_w = std::max(name_w, s.name.size());
      unit_w = std::max(unit_w, output_unit(s.dimension, U).name.size());
    }
    std::map<Dimension, double> largest;
    for (const Series& s : series)
      largest[s.dimension] = std::max({largest[s.dimension], std::abs(s.max), std::abs(s.min)});
    auto clean = [&](Dimension d, double v) { return std::abs(v) < 1e-12 * largest[d] ? 0.0 : v; };
    char line[400];
    const int nw = static_cast<int>(name_w), uw = static_cast<int>(unit_w);
    std::snprintf(line, sizeof line, "%-*s  %-*s %12s %10s %12s %10s %12s\n", nw, "quantity", uw,
                  "unit", "max", "at t", "min", "at t", "RMS");
    out << line;
    for (size_t k = 0; k < series.size(); ++k) {
      const Series& s = series[k];
      const OutputUnit u = output_unit(s.dimension, U);
      const bool det = k < mo.drivers.size() || r.determinate[k - mo.drivers.size()];
      std::snprintf(line, sizeof line, "%-*s  %-*s %12.5g %10.4g %12.5g %10.4g %12.5g%s\n", nw,
                    s.name.c_str(), uw, u.name.c_str(), u.from_si(clean(s.dimension, s.max)),
                    time_u.from_si(s.t_max), u.from_si(clean(s.dimension, s.min)),
                    time_u.from_si(s.t_min),
                    u.from_si(clean(s.dimension, std::sqrt(s.sum2 / std::max(1, s.count)))),
                    det ? "" : "   indeterminate (minimum norm)");
      out << line;
    }
    out << "\nconvention: drive.<driver> is the driver's torque or force on its joint's second "
           "body; reactions are forces and moments on a joint's first body from its second (as "
           "for one driver). Every position: --json or --out.\n";
    std::cout << out.str();
  }
  return r.status == MultiDriveStatus::completed ? kOk : kNumerical;
}

}  // namespace orthomech::cli

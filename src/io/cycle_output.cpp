#include "orthomech/io/cycle_output.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/check.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/noise.hpp"
#include "orthomech/io/number_text.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

namespace {

std::string number(double v) { return number_text(v, kCsvDigits); }

// A CSV field: quoted when it holds a comma or a quote.
std::string field(const std::string& s) {
  if (s.find_first_of(",\"") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

constexpr size_t kDimensions = static_cast<size_t>(Dimension::frequency) + 1;

// What for_each_cell needs besides the position: the position columns, built once per table (at
// every position they were rebuilt: 6000 strings per position on the N = 1000 four-bar), and the
// buffers for q and the pose, reused.
struct CellScratch {
  explicit CellScratch(const Model& model) : columns(position_columns(model)), q(model.nq) {}
  std::vector<PositionColumn> columns;
  std::vector<double> pose;
  VecX q;
};

// Every cell of the CSV row of p after the limits-free columns, in CSV order, with its dimension
// and SI value: emit(dimension, value, reported); `reported` false leaves the cell empty (an
// unbridged change point; a component that diverges towards the change point a bridged position
// is next to).
template <class Emit>
void for_each_cell(const Model& model, const CycleResult& result,
                   const std::vector<ReactionMagnitude>& magnitudes, bool angular,
                   const DrivenPointView& p, CellScratch& scratch, Emit&& emit) {
  emit(angular ? Dimension::angle : Dimension::length, p.input, true);
  emit(Dimension::time, p.time, true);
  for (size_t i = 0; i < p.measures.size(); ++i)
    emit(dimension_of(model.measures[i].unit), p.measures[i], measure_reported(model, p, i));
  scratch.q = p.q;
  compute_output_positions(model, scratch.q, scratch.pose);
  for (size_t i = 0; i < scratch.pose.size(); ++i)
    emit(scratch.columns[i].dimension, scratch.pose[i], true);
  const bool rates = rates_reported(p);
  for (const Body& b : model.bodies) {
    for (int i = 0; i < b.nu(); ++i)
      emit(velocity_component(b, i).velocity_dimension, p.u(b.u_offset + i), rates);
    for (int i = 0; i < b.nu(); ++i)
      emit(velocity_component(b, i).acceleration_dimension, p.udot(b.u_offset + i), rates);
  }
  emit(angular ? Dimension::moment : Dimension::force, p.drive, drive_reported(p));
  for (size_t i = 0; i < p.reactions.size(); ++i)
    emit(dimension_of(result.components[i].unit), p.reactions[i], component_reported(result, p, i));
  for (const ReactionMagnitude& m : magnitudes)
    emit(dimension_of(m.unit), magnitude_at(p, m), magnitude_reported(result, p, m));
}

// A gnuplot single-quoted string.
std::string gp_string(const std::string& s) {
  std::string out = "'";
  for (const char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

}  // namespace

NoiseFloor cycle_noise_floor(const Model& model, const CycleResult& result,
                             const std::vector<ReactionMagnitude>& magnitudes, bool angular) {
  NoiseFloor noise;
  CellScratch scratch(model);
  for (const DrivenPointView& p : result.points)
    for_each_cell(model, result, magnitudes, angular, p, scratch,
                  [&](Dimension d, double v, bool reported) {
                    if (reported) noise.see(d, v);
                  });
  return noise;
}

namespace {

// Spatial bodies: the frame's origin x, y, z and orientation quaternion e0…e3 (as `pose:` in the
// file with `orientation: {quaternion: …}`), then every named point's x, y, z.
std::vector<PositionColumn> spatial_position_columns(const Model& model) {
  std::vector<PositionColumn> cols;
  for (const Body& b : model.bodies) {
    for (const char* c : {".x", ".y", ".z"}) cols.push_back({b.name + c, Dimension::length});
    for (const char* c : {".e0", ".e1", ".e2", ".e3"})
      cols.push_back({b.name + c, Dimension::none});
  }
  for (const Body& b : model.bodies)
    for (const auto& [name, local] : b.spatial.points)
      for (const char* c : {".x", ".y", ".z"})
        cols.push_back({b.name + "." + name + c, Dimension::length});
  return cols;
}

void spatial_output_positions(const Model& model, const VecX& q, std::vector<double>& out) {
  out.clear();
  for (const Body& b : model.bodies) {
    const Quat e = q.segment<4>(b.q_offset + 3).normalized();
    const Vec3 origin = q.segment<3>(b.q_offset) - rotation_matrix(e) * b.spatial.com_local;
    for (int k = 0; k < 3; ++k) out.push_back(origin(k));
    for (int k = 0; k < 4; ++k) out.push_back(e(k));
  }
  for (const Body& b : model.bodies) {
    const Quat e = q.segment<4>(b.q_offset + 3).normalized();
    const Mat3 R = rotation_matrix(e);
    const Vec3 origin = q.segment<3>(b.q_offset) - R * b.spatial.com_local;
    for (const auto& [name, local] : b.spatial.points) {
      const Vec3 r = origin + R * local;
      for (int k = 0; k < 3; ++k) out.push_back(r(k));
    }
  }
}

}  // namespace

const VelocityComponent& velocity_component(const Body& body, int i) {
  using D = Dimension;
  static const VelocityComponent kPlanar[] = {
      {"vx", "ax", D::velocity, D::acceleration},
      {"vy", "ay", D::velocity, D::acceleration},
      {"omega", "alpha", D::angular_velocity, D::angular_acceleration}};
  static const VelocityComponent kSpatial[] = {
      {"vx", "ax", D::velocity, D::acceleration},
      {"vy", "ay", D::velocity, D::acceleration},
      {"vz", "az", D::velocity, D::acceleration},
      {"wx", "alpha_x", D::angular_velocity, D::angular_acceleration},
      {"wy", "alpha_y", D::angular_velocity, D::angular_acceleration},
      {"wz", "alpha_z", D::angular_velocity, D::angular_acceleration}};
  return (body.kind == BodyKind::spatial ? kSpatial : kPlanar)[i];
}

std::vector<PositionColumn> position_columns(const Model& model) {
  if (model.dimension == 3) return spatial_position_columns(model);
  std::vector<PositionColumn> cols;
  for (const Body& b : model.bodies) {
    cols.push_back({b.name + ".x", Dimension::length});
    cols.push_back({b.name + ".y", Dimension::length});
    if (b.kind == BodyKind::rigid) cols.push_back({b.name + ".angle", Dimension::angle});
  }
  for (const Body& b : model.bodies)
    for (const auto& [name, local] : b.points) {
      cols.push_back({b.name + "." + name + ".x", Dimension::length});
      cols.push_back({b.name + "." + name + ".y", Dimension::length});
    }
  return cols;
}

void compute_output_positions(const Model& model, const VecX& q, std::vector<double>& out) {
  if (model.dimension == 3) {
    spatial_output_positions(model, q, out);
    return;
  }
  out.clear();
  // The body frame: q holds the centre of mass r_c and the angle φ; the frame's origin is
  // r_o = r_c − R(φ) c, c the centre of mass in the body frame; a point p of the body is at
  // r_o + R(φ) p.
  auto frame = [&](const Body& b, Vec2& origin, Eigen::Matrix2d& R) {
    const double phi = b.kind == BodyKind::rigid ? q(b.q_offset + 2) : 0.0;
    R << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
    origin = Vec2(q(b.q_offset), q(b.q_offset + 1)) - R * b.com_local;
    return phi;
  };
  Vec2 origin;
  Eigen::Matrix2d R;
  for (const Body& b : model.bodies) {
    const double phi = frame(b, origin, R);
    out.push_back(origin.x());
    out.push_back(origin.y());
    if (b.kind == BodyKind::rigid) out.push_back(phi);
  }
  for (const Body& b : model.bodies) {
    frame(b, origin, R);
    for (const auto& [name, local] : b.points) {
      const Vec2 r = origin + R * local;
      out.push_back(r.x());
      out.push_back(r.y());
    }
  }
}

std::vector<ExtraColumn> shaking_columns(const Model& model, const ShakingSeries& s) {
  std::vector<ExtraColumn> cols;
  const char* axes[3] = {"x", "y", "z"};
  const bool planar = model.dimension == 2;
  for (int part = 0; part < 2; ++part)
    for (int i = planar && part == 1 ? 2 : 0; i < (planar && part == 0 ? 2 : 3); ++i) {
      ExtraColumn c{std::string(part == 0 ? "shaking force " : "shaking moment ") + axes[i],
                    part == 0 ? Dimension::force : Dimension::moment,
                    {},
                    s.reported,
                    true};
      for (size_t k = 0; k < s.force.size(); ++k)
        c.values.push_back(part == 0 ? s.force[k](i) : s.moment[k](i));
      cols.push_back(std::move(c));
    }
  return cols;
}

std::vector<ExtraColumn> friction_columns(const Model& model, const CycleResult& result,
                                          const FrictionSeries& series, bool angular) {
  std::vector<ExtraColumn> cols;
  if (series.pins.empty()) return cols;
  ExtraColumn drive{"drive without friction",
                    angular ? Dimension::moment : Dimension::force,
                    {},
                    series.reported,
                    true};
  for (const DrivenPointView p : result.points) drive.values.push_back(p.drive_frictionless);
  cols.push_back(std::move(drive));
  for (size_t i = 0; i < series.pins.size(); ++i)
    cols.push_back(
        {model.joints[static_cast<size_t>(series.pins[i].joint)].name + " friction moment",
         Dimension::moment, series.moment[i], series.reported, true});
  cols.push_back({"friction power", Dimension::power, series.power, series.reported, true});
  if (series.bound.computed) {
    std::vector<bool> solved(series.reported.size());
    for (size_t k = 0; k < solved.size(); ++k)
      solved[k] = series.bound.reported[k] && std::isfinite(series.bound.drive[k]);
    cols.push_back({"drive at least friction", angular ? Dimension::moment : Dimension::force,
                    series.bound.drive, solved, true});
    cols.push_back({"least friction power", Dimension::power, series.bound.power, solved, true});
  }
  return cols;
}

CycleColumns write_cycle_csv(const std::filesystem::path& file, const Model& model,
                             const CycleResult& result,
                             const std::vector<ReactionMagnitude>& magnitudes, bool angular,
                             const UnitSystem& units, const std::vector<ExtraColumn>& extra) {
  CycleColumns cols;
  FileWriter target(file);  // rows streamed to a temporary file, put in place when complete
  std::ostream& out = target.stream();
  int col = 0;
  auto head = [&](const std::string& name, const OutputUnit& unit) {
    out << (col ? "," : "") << field(name + " [" + unit.name + "]");
    return ++col;
  };
  const OutputUnit input_unit = output_unit(angular ? Dimension::angle : Dimension::length, units);
  const OutputUnit time_unit = output_unit(Dimension::time, units);
  const OutputUnit drive_unit = output_unit(angular ? Dimension::moment : Dimension::force, units);
  cols.input_display = head("input", input_unit);
  head("time", time_unit);
  std::vector<OutputUnit> measure_units;
  for (const Measure& m : model.measures) {
    measure_units.push_back(output_unit(dimension_of(m.unit), units));
    head(m.name, measure_units.back());
  }
  const std::vector<PositionColumn> positions = position_columns(model);
  std::vector<OutputUnit> position_units;
  for (const PositionColumn& c : positions) {
    position_units.push_back(output_unit(c.dimension, units));
    head(c.name, position_units.back());
  }
  // Velocity and acceleration of every body's centre of mass, and angular ones.
  // The columns follow u and u̇ of the body: (vx, vy[, ω]) then (ax, ay[, α]).
  for (const Body& b : model.bodies) {
    for (int i = 0; i < b.nu(); ++i) {
      const VelocityComponent& c = velocity_component(b, i);
      head(b.name + "." + c.velocity, output_unit(c.velocity_dimension, units));
    }
    for (int i = 0; i < b.nu(); ++i) {
      const VelocityComponent& c = velocity_component(b, i);
      head(b.name + "." + c.acceleration, output_unit(c.acceleration_dimension, units));
    }
  }
  cols.drive = head("drive", drive_unit);
  std::vector<OutputUnit> component_units;
  for (const ReactionComponent& c : result.components) {
    component_units.push_back(output_unit(dimension_of(c.unit), units));
    head(c.name, component_units.back());
  }
  std::vector<OutputUnit> magnitude_units;
  for (const ReactionMagnitude& m : magnitudes) {
    const Dimension qm = dimension_of(m.unit);
    magnitude_units.push_back(output_unit(qm, units));
    const int c = head(m.name, magnitude_units.back());
    cols.magnitudes.push_back(c);
    (qm == Dimension::force ? cols.forces : cols.moments).push_back(c);
  }
  // The extra columns: those before `limits`, then `limits`, then the others.
  std::vector<OutputUnit> extra_units;
  for (const ExtraColumn& c : extra) {
    check_argument(c.values.size() == result.points.size() &&
                       (c.reported.empty() || c.reported.size() == c.values.size()),
                   "write_cycle_csv", "extra", "must have one value per position in every column");
    extra_units.push_back(output_unit(c.dimension, units));
  }
  for (const bool before : {true, false}) {
    if (!before) out << ",limits";
    for (size_t i = 0; i < extra.size(); ++i)
      if (extra[i].before_limits == before)
        out << ',' << field(extra[i].name + " [" + extra_units[i].name + "]");
  }
  out << '\n';
  const NoiseFloor noise = cycle_noise_floor(model, result, magnitudes, angular);
  std::array<OutputUnit, kDimensions> unit_of;
  for (size_t d = 0; d < kDimensions; ++d)
    unit_of[d] = output_unit(static_cast<Dimension>(d), units);
  CellScratch scratch(model);
  std::string line;  // one row's text (append_number: printf's "%.12g" without printf)
  for (size_t row = 0; row < result.points.size(); ++row) {
    const DrivenPointView p = result.points[row];
    line.clear();
    bool first = true;
    for_each_cell(
        model, result, magnitudes, angular, p, scratch, [&](Dimension d, double v, bool reported) {
          if (!first) line += ',';
          first = false;
          if (reported)
            append_number(line, unit_of[static_cast<size_t>(d)].from_si(noise.clean(d, v)),
                          kCsvDigits);
        });
    std::string outside;  // scratch.q is p.q (for_each_cell)
    for (size_t j = 0; j < model.joints.size(); ++j)
      if (outside_limits(model, static_cast<int>(j), scratch.q))
        outside += (outside.empty() ? "" : " ") + model.joints[j].name;
    for (const bool before : {true, false}) {
      if (!before) {
        line += ',';
        line += field(outside);
      }
      for (size_t i = 0; i < extra.size(); ++i) {
        if (extra[i].before_limits != before) continue;
        line += ',';
        if (extra[i].reported.empty() || extra[i].reported[row])
          append_number(line, extra_units[i].from_si(extra[i].values[row]), kCsvDigits);
      }
    }
    line += '\n';
    out.write(line.data(), static_cast<std::streamsize>(line.size()));
  }
  target.commit();
  return cols;
}

void write_cycle_gnuplot(const std::filesystem::path& script, const std::string& csv_name,
                         const Model& model, const CycleResult& result,
                         const std::vector<ReactionMagnitude>& magnitudes,
                         const CycleColumns& columns, bool angular, const UnitSystem& units,
                         const std::string& speed_text) {
  std::ostringstream gp;
  const OutputUnit input_unit = output_unit(angular ? Dimension::angle : Dimension::length, units);
  const std::string x =
      std::string(angular ? "input angle" : "input displacement") + " [" + input_unit.name + "]";
  gp << "# orthomech cycle: drive and joint reactions of " << model.name
     << " versus the input.\n# Run in this directory: gnuplot " << script.filename().string()
     << "\nset datafile separator ','\nset key outside right top\nset grid\n"
     << "set xlabel " << gp_string(x) << "\n";
  // The input axis over the sweep, from its start.
  if (result.points.size() >= 2) {
    double lo = input_unit.from_si(result.points.front().input);
    double hi = input_unit.from_si(result.points.back().input);
    if (lo > hi) std::swap(lo, hi);
    if (hi > lo) gp << "set xrange [" << number(lo) << ":" << number(hi) << "]\n";
  }
  // Dead and singular positions: dashed vertical lines.
  int arrow = 0;
  for (const auto* events : {&result.dead_points, &result.singular_positions})
    for (const DeadPoint& d : *events)
      gp << "set arrow " << ++arrow << " from first " << number(input_unit.from_si(d.input))
         << ", graph 0 to first " << number(input_unit.from_si(d.input))
         << ", graph 1 nohead dt 2 lc rgb 'gray40'\n";
  // Series told apart by colour and dash (more than eight lines stay distinguishable).
  auto style = [](size_t i) {
    return " lw 2 lc " + std::to_string(i % 8 + 1) + " dt " + std::to_string(i / 8 % 5 + 1);
  };
  auto plot_both = [&](const std::string& stem, const std::string& title, const std::string& ylabel,
                       const std::string& y2label, const std::string& plot) {
    gp << "set title " << gp_string(title) << "\nset ylabel " << gp_string(ylabel) << '\n';
    if (y2label.empty())
      gp << "unset y2label\nunset y2tics\nset ytics mirror\n";
    else
      gp << "set y2label " << gp_string(y2label) << "\nset y2tics\nset ytics nomirror\n";
    gp << "set terminal svg size 1000,560 dynamic\nset output " << gp_string(stem + ".svg") << '\n'
       << plot << '\n';
    gp << "set terminal pngcairo size 1000,560\nset output " << gp_string(stem + ".png") << '\n'
       << plot << "\nset output\n";
  };
  const OutputUnit drive_unit = output_unit(angular ? Dimension::moment : Dimension::force, units);
  const std::string title_tail = speed_text.empty() ? "" : " (" + speed_text + ")";
  plot_both("drive", model.name + ": drive" + title_tail, "drive [" + drive_unit.name + "]", "",
            "plot " + gp_string(csv_name) + " using " + std::to_string(columns.input_display) +
                ":" + std::to_string(columns.drive) + " with lines" + style(0) + " title 'drive'");
  // Forces on the left axis, moments on the right.
  const std::string force_unit = output_unit(Dimension::force, units).name;
  const std::string moment_unit = output_unit(Dimension::moment, units).name;
  std::string plot;
  for (size_t i = 0; i < magnitudes.size(); ++i) {
    const bool moment = std::find(columns.moments.begin(), columns.moments.end(),
                                  columns.magnitudes[i]) != columns.moments.end();
    plot += (i ? ", \\\n     " : "plot ") + gp_string(i ? std::string() : csv_name) + " using " +
            std::to_string(columns.input_display) + ":" + std::to_string(columns.magnitudes[i]) +
            (moment ? " axes x1y2" : "") + " with lines" + style(i) + " title " +
            gp_string(magnitudes[i].name + " [" + (moment ? moment_unit : force_unit) + "]" +
                      (magnitudes[i].determinate ? "" : " (min-norm)"));
  }
  if (!plot.empty())
    plot_both("reactions", model.name + ": joint reactions (magnitudes)" + title_tail,
              "force [" + force_unit + "]",
              columns.moments.empty() ? "" : "moment [" + moment_unit + "]", plot);
  write_file(script, gp.str());
}

}  // namespace orthomech

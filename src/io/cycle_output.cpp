#include "orthomech/io/cycle_output.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace orthomech {

namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  return buf;
}

// A CSV field: quoted when it holds a comma or a quote.
std::string field(const std::string& s) {
  if (s.find_first_of(",\"") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// A gnuplot single-quoted string.
std::string gp_string(const std::string& s) {
  std::string out = "'";
  for (const char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

}  // namespace

void write_file_atomically(const std::filesystem::path& file, const std::string& text) {
  const std::filesystem::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      throw std::runtime_error("cannot write " + file.string() + ": " + std::strerror(errno));
    out << text;
    out.flush();
    if (!out)
      throw std::runtime_error("cannot write " + file.string() + ": " + std::strerror(errno));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error("cannot write " + file.string() + ": " + ec.message());
  }
}

CycleColumns write_cycle_csv(const std::filesystem::path& file, const Model& model,
                             const CycleResult& result,
                             const std::vector<ReactionMagnitude>& magnitudes, bool angular,
                             const std::string& drive_unit) {
  CycleColumns cols;
  std::ostringstream out;
  int col = 0;
  out << (angular ? "input [rad],input [deg]" : "input [m],input [mm]") << ",time [s]";
  col = 3;
  for (const Measure& m : model.measures) out << ',' << field(m.name + " [" + m.unit + "]"), ++col;
  // Velocity and acceleration of every body's centre of mass, and angular ones.
  // The columns follow u and u̇ of the body: (vx, vy[, ω]) then (ax, ay[, α]).
  static const char* const kVelocity[] = {"vx [m/s]", "vy [m/s]", "omega [rad/s]"};
  static const char* const kAcceleration[] = {"ax [m/s^2]", "ay [m/s^2]", "alpha [rad/s^2]"};
  for (const Body& b : model.bodies) {
    for (int i = 0; i < b.nu(); ++i) out << ',' << field(b.name + "." + kVelocity[i]), ++col;
    for (int i = 0; i < b.nu(); ++i) out << ',' << field(b.name + "." + kAcceleration[i]), ++col;
  }
  out << ",drive [" << drive_unit << "]";
  cols.drive = ++col;
  for (const ReactionComponent& c : result.components)
    out << ',' << field(c.name + " [" + c.unit + "]"), ++col;
  for (const ReactionMagnitude& m : magnitudes) {
    out << ',' << field(m.name + " [" + m.unit + "]");
    cols.magnitudes.push_back(++col);
  }
  out << '\n';
  const double display = angular ? 180.0 / std::numbers::pi : 1e3;
  for (const DrivenPointView& p : result.points) {
    out << number(p.input) << ',' << number(p.input * display) << ',' << number(p.time);
    for (const double v : p.measures) out << ',' << number(v);
    for (const Body& b : model.bodies) {
      for (int i = 0; i < b.nu(); ++i) out << ',' << number(p.u(b.u_offset + i));
      for (int i = 0; i < b.nu(); ++i) out << ',' << number(p.udot(b.u_offset + i));
    }
    // Empty cells where a value is not reported (an unbridged change point; a component that
    // diverges towards the change point a bridged position is next to).
    out << ',';
    if (drive_reported(p)) out << number(p.drive);
    for (size_t i = 0; i < p.reactions.size(); ++i) {
      out << ',';
      if (component_reported(result, p, i)) out << number(p.reactions[i]);
    }
    for (const ReactionMagnitude& m : magnitudes) {
      out << ',';
      if (magnitude_reported(result, p, m)) out << number(magnitude_at(p, m));
    }
    out << '\n';
  }
  write_file_atomically(file, out.str());
  return cols;
}

void write_cycle_gnuplot(const std::filesystem::path& script, const std::string& csv_name,
                         const Model& model, const std::vector<ReactionMagnitude>& magnitudes,
                         const CycleColumns& columns, bool angular, const std::string& drive_unit) {
  std::ostringstream gp;
  const std::string x = angular ? "input angle [deg]" : "input displacement [mm]";
  gp << "# orthomech cycle: drive and joint reactions of " << model.name
     << " versus the input.\n# Run in this directory: gnuplot " << script.filename().string()
     << "\nset datafile separator ','\nset key outside right top\nset grid\n"
     << "set xlabel " << gp_string(x) << "\n";
  auto plot_both = [&](const std::string& stem, const std::string& title, const std::string& ylabel,
                       const std::string& plot) {
    gp << "set title " << gp_string(title) << "\nset ylabel " << gp_string(ylabel) << '\n';
    gp << "set terminal svg size 1000,560 dynamic\nset output " << gp_string(stem + ".svg") << '\n'
       << plot << '\n';
    gp << "set terminal pngcairo size 1000,560\nset output " << gp_string(stem + ".png") << '\n'
       << plot << "\nset output\n";
  };
  plot_both("drive", model.name + ": drive", "drive [" + drive_unit + "]",
            "plot " + gp_string(csv_name) + " using " + std::to_string(columns.input_display) +
                ":" + std::to_string(columns.drive) + " with lines lw 2 title 'drive'");
  std::string plot;
  for (size_t i = 0; i < magnitudes.size(); ++i) {
    plot += (i ? ", \\\n     " : "plot ") + gp_string(i ? std::string() : csv_name) + " using " +
            std::to_string(columns.input_display) + ":" + std::to_string(columns.magnitudes[i]) +
            " with lines lw 2 title " +
            gp_string(magnitudes[i].name + " [" + magnitudes[i].unit + "]" +
                      (magnitudes[i].determinate ? "" : " (min-norm)"));
  }
  if (!plot.empty())
    plot_both("reactions", model.name + ": joint reactions (magnitudes)", "reaction", plot);
  write_file_atomically(script, gp.str());
}

}  // namespace orthomech

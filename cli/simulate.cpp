// `orthomech simulate FILE --t-end T`: forward dynamics (issue 5; design §4–5, §8).
// All the mathematics is in dynamics/simulate; this file parses options and formats results.
#include "orthomech/dynamics/simulate.hpp"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/analysis/assembly.hpp"
#include "orthomech/io/cycle_output.hpp"
#include "orthomech/io/noise.hpp"
#include "orthomech/io/units.hpp"

namespace orthomech::cli {

namespace {

struct SimulateCliOptions {
  std::string file;
  std::vector<std::string> sets;  // --set PATH=VALUE
  double t_end = 1.0;
  double rtol = 1e-8, atol = 1e-10, dt_out = 0.0, max_step = 0.0;
  std::string form = "dual";
  std::string integrator = "dopri5";
  std::vector<std::string> rates;  // NAME=VALUE
  bool json = false;
  bool positions = false;
  std::string out_dir;
  std::string units = "file";
};

// Output units of every column of simulate (measures, reactions, energies, positions).
struct SimulateUnits {
  UnitSystem system;
  OutputUnit time, energy, length;
  std::vector<OutputUnit> measures, components, positions;
  std::vector<PositionColumn> position_columns;
  SimulateUnits(const Model& model, const SimulateResult& res, const UnitSystem& u)
      : system(u),
        time(output_unit(Dimension::time, u)),
        energy(output_unit(Dimension::moment, u)),
        length(output_unit(Dimension::length, u)),
        position_columns(orthomech::position_columns(model)) {
    for (const Measure& m : model.measures)
      measures.push_back(output_unit(dimension_of(m.unit), u));
    for (const auto& c : res.components) components.push_back(output_unit(dimension_of(c.unit), u));
    for (const PositionColumn& c : position_columns)
      positions.push_back(output_unit(c.dimension, u));
    angle = output_unit(Dimension::angle, u);
    // The scale of every dimension over the samples: rounding noise is written as 0
    // (io/noise.hpp; a slider's y on a horizontal guide, a frictionless slide's axial force).
    std::vector<double> pose;
    for (const SimulationSample& s : res.samples) {
      for (size_t k = 0; k < s.measures.size(); ++k)
        noise.see(dimension_of(model.measures[k].unit), s.measures[k]);
      for (size_t k = 0; k < s.reactions.size() && k < res.components.size(); ++k)
        noise.see(dimension_of(res.components[k].unit), s.reactions[k]);
      compute_output_positions(model, s.q, pose);
      for (size_t k = 0; k < pose.size(); ++k) noise.see(position_columns[k].dimension, pose[k]);
      for (const double e : {s.kinetic, s.potential, s.work}) noise.see(Dimension::moment, e);
    }
    for (const Measure& m : model.measures) measure_dims.push_back(dimension_of(m.unit));
    for (const auto& c : res.components) component_dims.push_back(dimension_of(c.unit));
  }
  OutputUnit angle;
  NoiseFloor noise;
  std::vector<Dimension> measure_dims, component_dims;
  // SI values to output values, rounding noise as 0: measure k, reaction component k, position
  // column k, an energy.
  [[nodiscard]] double measure(size_t k, double v) const {
    return measures[k].from_si(noise.clean(measure_dims[k], v));
  }
  [[nodiscard]] double component(size_t k, double v) const {
    return components[k].from_si(noise.clean(component_dims[k], v));
  }
  [[nodiscard]] double position(size_t k, double v) const {
    return positions[k].from_si(noise.clean(position_columns[k].dimension, v));
  }
  [[nodiscard]] double energy_of(double v) const {
    return energy.from_si(noise.clean(Dimension::moment, v));
  }
};

std::string g(double v, int precision = 10) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

// "B0_vx=1": the rate of a measure's position quantity, in the file's units (length or angle per
// time unit).
InitialRate parse_rate(const Model& model, const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos)
    throw CLI::ValidationError("--rate",
                               "--rate '" + text + "': expected MEASURE=VALUE (the file's units)");
  const std::string name = text.substr(0, eq);
  const int m = model.find_measure(name);
  if (m < 0)
    throw CLI::ValidationError("--rate",
                               "--rate '" + text + "': measure '" + name + "' is not defined");
  const UnitSystem file = unit_system(model.units);
  const bool angle = model.measures[static_cast<size_t>(m)].unit.rfind("rad", 0) == 0;
  const double scale = (angle ? file.angle_si : file.length_si) / file.time_si;
  return {m, parse_number(text.substr(eq + 1), "--rate " + name) * scale};
}

// simulate.csv: every column with its unit in the header (the output units), every body's pose
// and named point; chart_switches.csv.
void write_csv(const std::filesystem::path& dir, const Model& model, const SimulateResult& res,
               const SimulateUnits& U) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw CLI::ValidationError("--out", "cannot create " + dir.string() + ": " + ec.message());
  std::ofstream out(dir / "simulate.csv");
  out.precision(12);
  out << "t [" << U.time.name << "]";
  for (size_t k = 0; k < model.measures.size(); ++k)
    out << "," << model.measures[k].name << " [" << U.measures[k].name << "]";
  for (size_t k = 0; k < U.position_columns.size(); ++k)
    out << "," << U.position_columns[k].name << " [" << U.positions[k].name << "]";
  for (size_t k = 0; k < res.components.size(); ++k)
    out << "," << res.components[k].name << " [" << U.components[k].name << "]";
  const std::string e = " [" + U.energy.name + "]";
  out << ",kinetic" << e << ",potential" << e << ",work" << e << ",energy" << e
      << ",residual_length [" << U.length.name << "],residual_angle [" << U.angle.name << "]\n";
  std::vector<double> pose;
  for (const SimulationSample& s : res.samples) {
    out << U.time.from_si(s.t);
    for (size_t k = 0; k < s.measures.size(); ++k) out << "," << U.measure(k, s.measures[k]);
    compute_output_positions(model, s.q, pose);
    for (size_t k = 0; k < pose.size(); ++k) out << "," << U.position(k, pose[k]);
    for (size_t k = 0; k < res.components.size(); ++k)
      out << "," << (k < s.reactions.size() ? U.component(k, s.reactions[k]) : 0.0);
    const ResidualSplit r = split_residual(model, s.q);
    out << "," << U.energy_of(s.kinetic) << "," << U.energy_of(s.potential) << ","
        << U.energy_of(s.work) << "," << U.energy_of(s.kinetic + s.potential - s.work) << ","
        << U.length.from_si(r.length) << "," << U.angle.from_si(r.angle) << "\n";
  }
  std::ofstream sw(dir / "chart_switches.csv");
  sw << "t [" << U.time.name << "],from,to\n";
  for (const ChartSwitch& c : res.chart_switches)
    sw << g(U.time.from_si(c.t), 12) << ",\"" << c.from << "\",\"" << c.to << "\"\n";
  out.close();
  sw.close();
  if (!out || !sw) throw CLI::ValidationError("--out", "cannot write the files in " + dir.string());
}

// The time histories, one array per quantity over the output times (columns, as plotting tools
// read them; a tenth of the objects of one record per sample, measured: 100 samples of Andrews
// cost about 2.5 ms as records). With `positions`: every body's pose and named point too.
nlohmann::json series_json(const Model& model, const SimulateResult& res, const SimulateUnits& U,
                           bool positions) {
  const size_t ns = res.samples.size();
  const auto column = [&](auto&& value) {
    std::vector<double> c;
    c.reserve(ns);
    for (const SimulationSample& s : res.samples) c.push_back(value(s));
    return nlohmann::json(c);
  };
  nlohmann::json j;
  j["t"] = column([&](const SimulationSample& s) { return U.time.from_si(s.t); });
  nlohmann::json m = nlohmann::json::object();
  for (size_t k = 0; k < model.measures.size(); ++k)
    m[model.measures[k].name] =
        column([&, k](const SimulationSample& s) { return U.measure(k, s.measures[k]); });
  j["measures"] = m;
  nlohmann::json r = nlohmann::json::object();
  for (size_t k = 0; k < res.components.size(); ++k)
    r[res.components[k].name] = column([&, k](const SimulationSample& s) {
      return k < s.reactions.size() ? U.component(k, s.reactions[k]) : std::nan("");
    });
  j["reactions"] = r;
  j["kinetic"] = column([&](const SimulationSample& s) { return U.energy_of(s.kinetic); });
  j["potential"] = column([&](const SimulationSample& s) { return U.energy_of(s.potential); });
  j["work"] = column([&](const SimulationSample& s) { return U.energy_of(s.work); });
  j["residual_length"] = column([&](const SimulationSample& s) {
    return U.length.from_si(split_residual(model, s.q).length);
  });
  j["residual_angle"] = column(
      [&](const SimulationSample& s) { return U.angle.from_si(split_residual(model, s.q).angle); });
  if (positions) {
    std::vector<std::vector<double>> cols(U.position_columns.size());
    std::vector<double> pose;
    for (const SimulationSample& s : res.samples) {
      compute_output_positions(model, s.q, pose);
      for (size_t k = 0; k < pose.size(); ++k) cols[k].push_back(U.position(k, pose[k]));
    }
    nlohmann::json p = nlohmann::json::object();
    for (size_t k = 0; k < cols.size(); ++k) p[U.position_columns[k].name] = cols[k];
    j["positions"] = p;
  }
  return j;
}

nlohmann::json sample_json(const Model& model, const SimulateResult& res, const SimulationSample& s,
                           const SimulateUnits& U) {
  nlohmann::json j;
  j["t"] = U.time.from_si(s.t);
  nlohmann::json m = nlohmann::json::object();
  // (A final sample at a stop where no equation holds carries no measures: written as none.)
  for (size_t k = 0; k < model.measures.size() && k < s.measures.size(); ++k)
    m[model.measures[k].name] = U.measure(k, s.measures[k]);
  j["measures"] = m;
  nlohmann::json r = nlohmann::json::object();
  for (size_t k = 0; k < s.reactions.size() && k < res.components.size(); ++k)
    r[res.components[k].name] = U.component(k, s.reactions[k]);
  j["reactions"] = r;
  j["kinetic"] = U.energy_of(s.kinetic);
  j["potential"] = U.energy_of(s.potential);
  j["work"] = U.energy_of(s.work);
  const ResidualSplit split = split_residual(model, s.q);
  j["residual_length"] = U.length.from_si(split.length);
  j["residual_angle"] = U.angle.from_si(split.angle);
  return j;
}

// The library's options from the command line's (times in the file's unit).
SimulateOptions simulate_options(const Model& model, const SimulateCliOptions& opt) {
  const double file_time = unit_system(model.units).time_si;  // bare times: the file's unit
  SimulateOptions so;
  so.t_end = opt.t_end * file_time;
  so.rtol = opt.rtol;
  so.atol = opt.atol;
  so.dt_out = opt.dt_out * file_time;
  so.max_step = opt.max_step * file_time;
  so.form = opt.form == "primal" ? DynamicsForm::primal : DynamicsForm::dual;
  if (!parse_integrator(opt.integrator, so.integrator))  // CLI::IsMember checked the name
    throw std::logic_error("simulate: integrator '" + opt.integrator + "' has no stepper");
  for (const std::string& r : opt.rates) so.initial_rates.push_back(parse_rate(model, r));
  so.record_samples = true;
  return so;
}

double relative_drift(const SimulateResult& res) {
  return res.energy_scale > 0 ? res.energy_max_drift / res.energy_scale : 0.0;
}

// The chart switches and the change points passed, as JSON arrays.
nlohmann::json chart_switches_json(const SimulateResult& res, const SimulateUnits& U) {
  nlohmann::json sw = nlohmann::json::array();
  for (const ChartSwitch& c : res.chart_switches)
    sw.push_back({{"t", U.time.from_si(c.t)}, {"from", c.from}, {"to", c.to}});
  return sw;
}
nlohmann::json passages_json(const SimulateResult& res, const SimulateUnits& U) {
  nlohmann::json cp = nlohmann::json::array();
  for (const ChangePointPassage& c : res.passages)
    cp.push_back({{"t", U.time.from_si(c.t)},
                  {"from", U.time.from_si(c.t_from)},
                  {"to", U.time.from_si(c.t_to)},
                  {"quality_from", c.sigma_from},
                  {"quality_to", c.sigma_to},
                  {"velocity_jump", c.velocity_jump},
                  {"tangent_cosine", c.tangent_cosine}});
  return cp;
}

// The --json document.
nlohmann::json result_json(const Model& model, const UnitSystem& system, const SimulateOptions& so,
                           const SimulateResult& res, const SimulateUnits& U, bool positions) {
  nlohmann::json j;
  j["mechanism"] = model.name;
  j["units"] = units_json(system);
  j["status"] = to_string(res.status);
  j["message"] = res.message;
  j["form"] = so.form == DynamicsForm::dual ? "dual" : "primal";
  j["integrator"] = to_string(so.integrator);
  j["rtol"] = so.rtol;
  j["atol"] = so.atol;
  j["final"] = sample_json(model, res, res.final, U);
  j["energy"] = {{"initial", U.energy.from_si(res.energy_initial)},
                 {"final", U.energy.from_si(res.energy_final)},
                 {"max_drift", U.energy.from_si(res.energy_max_drift)},
                 {"relative_drift", relative_drift(res)}};
  j["max_residual_length"] = U.length.from_si(res.max_residual_length);
  j["max_residual_angle"] = U.angle.from_si(res.max_residual_angle);
  j["max_velocity_residual"] = res.max_velocity_residual;
  if (so.form == DynamicsForm::primal) j["max_invariant_J"] = res.max_invariant_J;
  j["kinetic_energy_removed"] = U.energy.from_si(res.kinetic_removed);
  j["steps"] = res.steps;
  j["evaluations"] = res.evaluations;
  j["rejected_steps"] = res.rejected_steps;
  j["jacobians"] = res.jacobians;
  j["chart_switches"] = chart_switches_json(res, U);
  j["change_points_passed"] = res.passages.size();
  j["change_points"] = passages_json(res, U);
  j["samples"] = series_json(model, res, U, positions);
  return j;
}

// The text report: a summary, then one line per output time.
void write_text(std::ostream& out, const Model& model, const SimulateCliOptions& opt,
                const SimulateOptions& so, const SimulateResult& res, const SimulateUnits& U) {
  out << "mechanism   " << model.name << "  (" << model.file << ")\n";
  out << "form        " << opt.form << ", " << opt.integrator << ", rtol " << g(so.rtol, 3)
      << ", atol " << g(so.atol, 3) << "\n";
  out << "status      " << to_string(res.status) << (res.message.empty() ? "" : ": ") << res.message
      << "\n";
  out << "steps       " << res.steps << " (" << res.evaluations << " evaluations";
  if (res.rejected_steps > 0) out << ", " << res.rejected_steps << " rejected";
  if (res.jacobians > 0) out << ", " << res.jacobians << " Jacobians";
  out << "), " << res.passages.size() << " change points passed\n";
  const std::string eu = " " + U.energy.name;
  out << "energy      initial " << g(U.energy.from_si(res.energy_initial)) << eu << ", final "
      << g(U.energy.from_si(res.energy_final)) << eu << ", max drift "
      << g(U.energy.from_si(res.energy_max_drift), 3) << eu << " (relative "
      << g(relative_drift(res), 3) << ")\n";
  out << "residual    max |f| " << g(U.length.from_si(res.max_residual_length), 3) << " "
      << U.length.name << " (length rows), " << g(U.angle.from_si(res.max_residual_angle), 3) << " "
      << U.angle.name << " (angular rows)";
  if (so.form == DynamicsForm::primal) out << ", max |J| " << g(res.max_invariant_J, 3);
  out << "\n\n";
  out << "t [" << U.time.name << "]";
  for (size_t k = 0; k < model.measures.size(); ++k)
    out << "\t" << model.measures[k].name << " [" << U.measures[k].name << "]";
  out << "\tenergy [" << U.energy.name << "]\n";
  for (const SimulationSample& s : res.samples) {
    out << g(U.time.from_si(s.t), 6);
    for (size_t k = 0; k < s.measures.size(); ++k) out << "\t" << g(U.measure(k, s.measures[k]), 8);
    out << "\t" << g(U.energy_of(s.kinetic + s.potential - s.work), 8) << "\n";
  }
}

int run_simulate(const SimulateCliOptions& opt) {
  const Model model = load(opt.file, opt.sets);
  const UnitSystem system = resolve_units(model, opt.units);
  const SimulateOptions so = simulate_options(model, opt);
  const SimulateResult res = simulate(model, so);
  const SimulateUnits U(model, res, system);
  if (res.kinetic_removed > 0.0)
    spdlog::info("initial velocity projection removed {:.6g} {} of kinetic energy",
                 U.energy.from_si(res.kinetic_removed), U.energy.name);
  if (!opt.out_dir.empty()) write_csv(opt.out_dir, model, res, U);
  spdlog::info(
      "{} chart switches: the dual form changed its independent velocities {} times (bookkeeping "
      "of the method; the results do not depend on it)",
      model.file, res.chart_switches.size());

  std::ostringstream out;
  const bool ok = res.status == SimulateStatus::completed;
  if (opt.json)
    out << result_json(model, system, so, res, U, opt.positions).dump(2) << '\n';
  else
    write_text(out, model, opt, so, res, U);
  std::cout << out.str();
  if (!ok) spdlog::error("simulate: {}: {}", to_string(res.status), res.message);
  return ok ? kOk : kNumerical;
}

}  // namespace

void register_simulate(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<SimulateCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "simulate", "forward dynamics: time histories of measures, reactions, energy, residuals");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  add_set_option(cmd, opt->sets);
  cmd->add_option("--t-end", opt->t_end, "end time, in the file's time unit")
      ->required()
      ->check(finite_range(0.0, kMaxGeneral, true));
  cmd->add_option("--rtol", opt->rtol, "relative tolerance")->check(finite_range(1e-15, 1.0));
  cmd->add_option("--atol", opt->atol, "absolute tolerance")->check(finite_range(0.0, 1e6, true));
  cmd->add_option("--dt-out", opt->dt_out,
                  "output interval (the file's time unit; default t_end/100; at most 1e6 output "
                  "samples)")
      ->check(finite_range(0.0, kMaxGeneral, true));
  cmd->add_option("--max-step", opt->max_step, "largest step (the file's time unit)")
      ->check(finite_range(0.0, kMaxGeneral, true));
  cmd->add_option("--form", opt->form, "dual (default) or primal (Theorem 7)")
      ->check(CLI::IsMember({"dual", "primal"}));
  cmd->add_option("--integrator", opt->integrator,
                  "dopri5 (default), rkf78, bulirsch-stoer (long runs, tight tolerances) or "
                  "rosenbrock4 (stiff)")
      ->check(CLI::IsMember({"dopri5", "rkf78", "bulirsch-stoer", "rosenbrock4"}));
  cmd->add_option("--rate", opt->rates,
                  "initial rate MEASURE=VALUE of a measure's position quantity, in the file's "
                  "declared units (length or angle per time unit); repeatable");
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  cmd->add_flag("--positions", opt->positions,
                "with --json: every body's pose and named point at every output time");
  cmd->add_option("--out", opt->out_dir, "directory for simulate.csv and chart_switches.csv");
  add_units_option(cmd, opt->units);
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    if (opt->dt_out > 0.0 && opt->t_end / opt->dt_out + 1.0 > kMaxOutputSamples)
      throw CLI::ValidationError("--dt-out",
                                 "--t-end / --dt-out gives more than 1e6 output "
                                 "samples; give a larger --dt-out");
    setup_logging(globals, *log);
    exit_code = run_simulate(*opt);
  });
}

}  // namespace orthomech::cli

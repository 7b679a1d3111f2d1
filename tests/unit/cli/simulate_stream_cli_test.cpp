// `simulate --json` and `--out` stream their samples (issue 18 item 2): the CLI keeps no sample in
// memory (SimulateOptions::on_sample into a temporary file). Oracle: the document and the CSV
// built the way the CLI built them before, from a SimulateResult that recorded every sample
// (record_samples = true), written here from the library's result with the documented rules
// (docs/cli.md: output units, rounding noise as 0 against the whole output's scale, the samples
// as columns). A run that stops (exit 3) is written whole as well.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/cycle_output.hpp"
#include "orthomech/io/noise.hpp"
#include "orthomech/io/units.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

using nlohmann::json;

// The output conversion of one run: units of the file, noise scale over every recorded sample.
struct Reference {
  const Model& model;
  const SimulateResult& res;
  UnitSystem system;
  std::vector<PositionColumn> columns;
  NoiseFloor noise;

  Reference(const Model& m, const SimulateResult& r)
      : model(m), res(r), system(output_units(m, "file")), columns(position_columns(m)) {
    std::vector<double> pose;
    for (const SimulationSample& s : res.samples) {
      for (size_t k = 0; k < s.measures.size(); ++k)
        noise.see(dimension_of(model.measures[k].unit), s.measures[k]);
      for (size_t k = 0; k < s.reactions.size(); ++k)
        noise.see(dimension_of(res.components[k].unit), s.reactions[k]);
      compute_output_positions(model, s.q, pose);
      for (size_t k = 0; k < pose.size(); ++k) noise.see(columns[k].dimension, pose[k]);
      for (const double e : {s.kinetic, s.potential, s.work}) noise.see(Dimension::moment, e);
    }
  }
  [[nodiscard]] double out(Dimension d, double v, bool clean = true) const {
    return output_unit(d, system).from_si(clean ? noise.clean(d, v) : v);
  }
  [[nodiscard]] double measure(size_t k, double v) const {
    return out(dimension_of(model.measures[k].unit), v);
  }
  [[nodiscard]] double reaction(size_t k, double v) const {
    return out(dimension_of(res.components[k].unit), v);
  }
  [[nodiscard]] double energy(double v) const { return out(Dimension::moment, v); }
  [[nodiscard]] double time(double v) const { return out(Dimension::time, v, false); }
  [[nodiscard]] double length(double v) const { return out(Dimension::length, v, false); }
  [[nodiscard]] double angle(double v) const { return out(Dimension::angle, v, false); }

  [[nodiscard]] json sample(const SimulationSample& s) const {
    json j;
    j["t"] = time(s.t);
    json m = json::object();
    for (size_t k = 0; k < s.measures.size(); ++k)
      m[model.measures[k].name] = measure(k, s.measures[k]);
    j["measures"] = m;
    json r = json::object();
    for (size_t k = 0; k < s.reactions.size(); ++k)
      r[res.components[k].name] = reaction(k, s.reactions[k]);
    j["reactions"] = r;
    j["kinetic"] = energy(s.kinetic);
    j["potential"] = energy(s.potential);
    j["work"] = energy(s.work);
    const ResidualSplit split = split_residual(model, s.q);
    j["residual_length"] = length(split.length);
    j["residual_angle"] = angle(split.angle);
    return j;
  }

  // The columns of `samples`, every body's pose and named point included.
  [[nodiscard]] json series() const {
    json j;
    std::vector<double> pose;
    for (const SimulationSample& s : res.samples) {
      const json one = sample(s);
      for (const char* key :
           {"t", "kinetic", "potential", "work", "residual_length", "residual_angle"})
        j[key].push_back(one[key]);
      for (size_t k = 0; k < model.measures.size(); ++k)
        j["measures"][model.measures[k].name].push_back(one["measures"][model.measures[k].name]);
      for (size_t k = 0; k < res.components.size(); ++k)
        j["reactions"][res.components[k].name].push_back(
            k < s.reactions.size() ? reaction(k, s.reactions[k]) : std::nan(""));
      compute_output_positions(model, s.q, pose);
      for (size_t k = 0; k < pose.size(); ++k)
        j["positions"][columns[k].name].push_back(out(columns[k].dimension, pose[k]));
    }
    return j;
  }

  [[nodiscard]] json document(const SimulateOptions& so) const {
    const auto unit = [&](Dimension d) { return output_unit(d, system).name; };
    json j;
    j["mechanism"] = model.name;
    j["units"] = {{"length", unit(Dimension::length)},
                  {"angle", unit(Dimension::angle)},
                  {"mass", unit(Dimension::mass)},
                  {"time", unit(Dimension::time)},
                  {"force", unit(Dimension::force)},
                  {"moment", unit(Dimension::moment)},
                  {"energy", unit(Dimension::moment)},
                  {"power", unit(Dimension::power)},
                  {"velocity", unit(Dimension::velocity)},
                  {"angular_velocity", unit(Dimension::angular_velocity)},
                  {"acceleration", unit(Dimension::acceleration)},
                  {"angular_acceleration", unit(Dimension::angular_acceleration)},
                  {"inertia", unit(Dimension::inertia)}};
    j["status"] = to_string(res.status);
    j["message"] = res.message;
    j["complete"] = res.status != SimulateStatus::stopped;
    if (res.status == SimulateStatus::stopped) j["stop"] = to_string(res.stop);
    j["form"] = so.form == DynamicsForm::dual ? "dual" : "primal";
    j["integrator"] = to_string(so.integrator);
    j["rtol"] = so.rtol;
    j["atol"] = so.atol;
    j["final"] = sample(res.final);
    j["energy"] = {
        {"initial", out(Dimension::moment, res.energy_initial, false)},
        {"final", out(Dimension::moment, res.energy_final, false)},
        {"max_drift", out(Dimension::moment, res.energy_max_drift, false)},
        {"relative_drift", res.energy_scale > 0 ? res.energy_max_drift / res.energy_scale : 0.0},
        {"drift_limit", res.energy_drift_limit},
        {"balance", res.status == SimulateStatus::completed      ? "held"
                    : res.status == SimulateStatus::energy_drift ? "drifted"
                                                                 : "unknown"}};
    j["limits_left"] = json::array();
    for (const LimitExit& e : res.limits_left) {
      const Joint& joint = model.joints[static_cast<size_t>(e.joint)];
      const Dimension d = joint_coordinate_kind(joint) == CoordinateKind::angle ? Dimension::angle
                                                                                : Dimension::length;
      const OutputUnit u = output_unit(d, system);
      j["limits_left"].push_back(
          {{"joint", joint.name},
           {"unit", u.name},
           {"limits", {u.from_si(joint.limits->x()), u.from_si(joint.limits->y())}},
           {"t_first", time(e.t_first)},
           {"first", u.from_si(e.value_first)},
           {"t_furthest", time(e.t_furthest)},
           {"furthest", u.from_si(e.value_furthest)},
           {"steps", e.steps}});
    }
    j["load_switches"] = res.load_switches;
    j["friction_switches"] = res.friction_switches;
    j["impacts"] = json::array();  // (no end stops in the bundled files streamed here)
    j["contacts"] = json::array();
    j["max_residual_length"] = length(res.max_residual_length);
    j["max_residual_angle"] = angle(res.max_residual_angle);
    j["max_velocity_residual"] = res.max_velocity_residual;
    if (so.form == DynamicsForm::primal) j["max_invariant_J"] = res.max_invariant_J;
    j["kinetic_energy_removed"] = out(Dimension::moment, res.kinetic_removed, false);
    j["steps"] = res.steps;
    j["evaluations"] = res.evaluations;
    j["rejected_steps"] = res.rejected_steps;
    j["jacobians"] = res.jacobians;
    j["chart_switches"] = json::array();
    for (const ChartSwitch& c : res.chart_switches)
      j["chart_switches"].push_back({{"t", time(c.t)}, {"from", c.from}, {"to", c.to}});
    j["change_points_passed"] = res.passages.size();
    j["change_points"] = json::array();
    for (const ChangePointPassage& c : res.passages)
      j["change_points"].push_back({{"t", time(c.t)},
                                    {"from", time(c.t_from)},
                                    {"to", time(c.t_to)},
                                    {"quality_from", c.sigma_from},
                                    {"quality_to", c.sigma_to},
                                    {"velocity_jump", c.velocity_jump},
                                    {"tangent_cosine", c.tangent_cosine},
                                    {"energy_balance", c.energy_balance}});
    j["samples"] = series();
    return json::parse(j.dump());  // as written: NaN as null, numbers round-tripped
  }

  [[nodiscard]] std::string csv() const {
    std::ostringstream o;
    o.precision(12);
    const auto unit = [&](Dimension d) { return " [" + output_unit(d, system).name + "]"; };
    o << "t" << unit(Dimension::time);
    for (const Measure& m : model.measures) o << "," << m.name << unit(dimension_of(m.unit));
    for (const PositionColumn& c : columns) o << "," << c.name << unit(c.dimension);
    for (const auto& c : res.components) o << "," << c.name << unit(dimension_of(c.unit));
    const std::string e = unit(Dimension::moment);
    o << ",kinetic" << e << ",potential" << e << ",work" << e << ",energy" << e
      << ",residual_length" << unit(Dimension::length) << ",residual_angle"
      << unit(Dimension::angle) << "\n";
    std::vector<double> pose;
    for (const SimulationSample& s : res.samples) {
      o << time(s.t);
      for (size_t k = 0; k < s.measures.size(); ++k) o << "," << measure(k, s.measures[k]);
      compute_output_positions(model, s.q, pose);
      for (size_t k = 0; k < pose.size(); ++k) o << "," << out(columns[k].dimension, pose[k]);
      for (size_t k = 0; k < res.components.size(); ++k)
        o << "," << (k < s.reactions.size() ? reaction(k, s.reactions[k]) : 0.0);
      const ResidualSplit r = split_residual(model, s.q);
      o << "," << energy(s.kinetic) << "," << energy(s.potential) << "," << energy(s.work) << ","
        << energy(s.kinetic + s.potential - s.work) << "," << length(r.length) << ","
        << angle(r.angle) << "\n";
    }
    return o.str();
  }
};

// Runs `simulate FILE args --json --positions --out DIR` and compares its document and
// simulate.csv with those built from the library's recorded run of the same options.
void expect_streamed_equals_recorded(const std::string& name, const std::vector<std::string>& args,
                                     const SimulateOptions& so, int exit_status) {
  const test::TempDir dir("orthomech_stream_");
  std::vector<std::string> cmd = {"simulate", test::bundled_file(name)};
  cmd.insert(cmd.end(), args.begin(), args.end());
  for (const char* a : {"--json", "--positions", "--out"}) cmd.emplace_back(a);
  cmd.push_back(dir.path.string());
  const auto r = test::run_cli(cmd);
  ASSERT_EQ(r.status, exit_status) << r.err;

  const Model model = test::load_bundled(name);
  SimulateOptions rec = so;
  rec.record_samples = true;
  const SimulateResult res = simulate(model, rec);
  ASSERT_FALSE(res.samples.empty());
  const Reference ref(model, res);

  const json doc = json::parse(r.out);  // valid JSON, whole
  const json expected = ref.document(so);
  ASSERT_EQ(doc.size(), expected.size());
  for (const auto& [key, value] : expected.items()) {
    ASSERT_TRUE(doc.contains(key)) << key;
    EXPECT_EQ(doc[key], value) << key << ": " << json::diff(value, doc[key]).dump().substr(0, 400);
  }
  EXPECT_EQ(doc["samples"]["t"].size(), res.samples.size());
  EXPECT_EQ(test::read_text(dir.path / "simulate.csv"), ref.csv());
}

TEST(SimulateStreamCli, CrankRocker_JsonAndCsvEqualTheRecordedRun) {
  SimulateOptions so;
  so.t_end = 0.2;
  so.dt_out = 1e-3;
  expect_streamed_equals_recorded("crank-rocker", {"--t-end", "0.2", "--dt-out", "0.001"}, so, 0);
}

// The primal form stops before the first change point of the N = 40 bar (t ≈ 0.7 s, singular):
// exit 3, and the document and the CSV still hold every output up to the stop. About 700 outputs
// of 1061 columns (5.9 MB of values): more than one 4 MB block of the CLI's column table, so the
// columns pass through its temporary file, the last block partly filled.
TEST(SimulateStreamCli, StoppedRun_JsonWholeAndCsvWithEveryOutput) {
  SimulateOptions so;  // the file's initial rates, as the CLI (simulate() takes them)
  so.form = DynamicsForm::primal;
  so.t_end = 1.0;
  so.dt_out = 1e-3;
  expect_streamed_equals_recorded("n-four-bar-40",
                                  {"--t-end", "1", "--dt-out", "0.001", "--form", "primal"}, so, 3);
}

}  // namespace
}  // namespace orthomech

// `orthomech simulate` contract (docs/cli.md): exit codes, the documented JSON keys (final.t,
// final.measures.<name>, energy, max_constraint_residual), CSV output.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "support/andrews_reference.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

using test::run_cli;

TEST(SimulateCli, AndrewsJsonHasTheDocumentedKeys) {
  const auto r = run_cli({"simulate", test::source_path("mechanisms/andrews-squeezer.yaml"),
                          "--t-end", "0.03", "--rtol", "1e-10", "--atol", "1e-12", "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "completed");
  EXPECT_NEAR(j["final"]["t"].get<double>(), 0.03, 1e-15);
  // Published β(0.03) (references.md §1), relative 1e-8.
  const double beta = test::andrews::kAnglesT003[0];  // published (references.md §1)
  EXPECT_NEAR(j["final"]["measures"]["beta"].get<double>(), beta, 1e-8 * beta);
  EXPECT_TRUE(j["energy"].contains("initial"));
  EXPECT_TRUE(j["energy"].contains("final"));
  EXPECT_LT(j["energy"]["max_drift"].get<double>(), 1e-8);
  // Andrews is in m/rad: the residual of the length rows in m; it has no angular row.
  EXPECT_LT(j["max_residual_length"].get<double>(), 1e-9);
  EXPECT_EQ(j["max_residual_angle"].get<double>(), 0.0);
  // Time histories as columns: t = 0, 0.0003, …, 0.03, and every measure, reaction component
  // and energy over the same times; the last entry is the final state.
  const auto& s = j["samples"];
  ASSERT_EQ(s["t"].size(), 101u);
  EXPECT_NEAR(s["t"][100].get<double>(), 0.03, 1e-15);
  EXPECT_NEAR(s["t"][1].get<double>(), 0.0003, 1e-15);
  for (const char* key : {"kinetic", "potential", "work", "residual_length", "residual_angle"})
    EXPECT_EQ(s[key].size(), 101u);
  ASSERT_EQ(s["measures"].size(), j["final"]["measures"].size());
  for (const auto& [name, column] : s["measures"].items()) {
    ASSERT_EQ(column.size(), 101u) << name;
    EXPECT_NEAR(column[100].get<double>(), j["final"]["measures"][name].get<double>(),
                1e-9 * (1.0 + std::abs(j["final"]["measures"][name].get<double>())))
        << name;
  }
  ASSERT_EQ(s["reactions"].size(), j["final"]["reactions"].size());
  for (const auto& [name, column] : s["reactions"].items()) EXPECT_EQ(column.size(), 101u) << name;
  EXPECT_NEAR(s["measures"]["beta"][0].get<double>(), test::andrews::kAnglesT0[0], 1e-9);
}

TEST(SimulateCli, PrimalFormAndCsv) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("orthomech_sim_" + std::to_string(::getpid()));
  const auto r = run_cli({"simulate", test::source_path("mechanisms/pendulum.yaml"), "--t-end", "1",
                          "--dt-out", "0.5", "--form", "primal", "--out", dir.string()});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string csv = test::read_text(dir / "simulate.csv");
  EXPECT_NE(csv.find("t [s],P1_x [m],P1_y [m]"), std::string::npos);
  // Three rows (t = 0, 0.5, 1) after the header.
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4);
  std::filesystem::remove_all(dir);
}

// The primal form where G = EᵀAE is singular at the start (the triple-crank's redundant rows, a
// spatial loop): exit 3 with the reason and a whole JSON document (it crashed reading the final
// sample's measures), never a crash.
TEST(SimulateCli, PrimalFormSingularAtTheStartExitsThreeWithJson) {
  for (const char* name : {"triple-crank", "hooke-joint"}) {
    const auto r =
        run_cli({"simulate", test::source_path(std::string("mechanisms/") + name + ".yaml"),
                 "--t-end", "1", "--form", "primal", "--json"});
    ASSERT_EQ(r.status, 3) << name << ": " << r.err;
    EXPECT_NE(r.err.find("G = EᵀAE is singular at t = 0"), std::string::npos) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("status"), "singular") << name;
    EXPECT_EQ(j.at("final").at("t"), 0.0) << name;
  }
}

TEST(SimulateCli, BadRateIsBadInput) {
  const auto r = run_cli({"simulate", test::source_path("mechanisms/pendulum.yaml"), "--t-end", "1",
                          "--rate", "nosuch=1"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("measure 'nosuch' is not defined"), std::string::npos) << r.err;
}

TEST(SimulateCli, MissingTEndIsBadInput) {
  const auto r = run_cli({"simulate", test::source_path("mechanisms/pendulum.yaml")});
  EXPECT_EQ(r.status, 2);
}

}  // namespace
}  // namespace orthomech

namespace orthomech {
namespace {

TEST(SimulateCli, KnucklePressFormsAndRestsOnItsCylindersEndStop) {
  // Issue 49's press in free motion: a 8 kN cylinder pressure against a throttle (a damper of
  // 40 N*s/mm along the cylinder) presses the ram down through the forming force; the cylinder
  // meets its end stop at 680 mm (restitution 0.2), comes to rest on it and is held there, the
  // ram at the height the toggle's geometry gives at 680 mm: 600 − 2√(300² − x_K²) with
  // |C − K| = 680 mm (bisection here). Both forms, the same contact time; the balance held.
  auto knee_y = [](double x) { return 600.0 - std::sqrt(300.0 * 300.0 - x * x); };
  double lo = 0.0, hi = 299.0;
  for (int it = 0; it < 200; ++it) {
    const double x = 0.5 * (lo + hi);
    (std::hypot(x - 700.0, knee_y(x) - 330.0) > 680.0 ? lo : hi) = x;
  }
  const double x_k = 0.5 * (lo + hi);
  const double y_min = 600.0 - 2.0 * std::sqrt(300.0 * 300.0 - x_k * x_k);
  const std::string loads =
      "loads=[{name: weight, type: gravity, g: [0, -9810]}, {name: forming, type: force, point: "
      "ram.P, force: [0, 20000], table: {measure: ram_y, points: [[0, 1], [6, 1], [6.5, 0]]}, "
      "active_while: {measure: ram_y, velocity: negative}}, {name: pressure, type: force, point: "
      "rod.K, force: [8000, 0], frame: body}, {name: throttle, type: spring-damper, connects: "
      "[barrel.C, rod.K], stiffness: 0, damping: 40}]";
  double t_from[2] = {0.0, 0.0};
  int k = 0;
  for (const char* form : {"dual", "primal"}) {
    SCOPED_TRACE(form);
    const auto r = run_cli({"simulate", test::bundled_file("knuckle-press"), "--t-end", "1",
                            "--form", form, "--set", loads, "--json", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["status"], "completed");
    EXPECT_EQ(j["energy"]["balance"], "held");
    EXPECT_GE(j["impacts"].size(), 1u);
    EXPECT_GE(j["load_switches"].get<long>(), 1);
    ASSERT_EQ(j["contacts"].size(), 1u) << j["contacts"];
    EXPECT_EQ(j["contacts"][0]["joint"], "cylinder");
    EXPECT_EQ(j["contacts"][0]["stop"], "upper");
    EXPECT_TRUE(j["contacts"][0]["t_to"].is_null());
    t_from[k++] = j["contacts"][0]["t_from"].get<double>();
    EXPECT_NEAR(j["final"]["measures"]["cylinder_length"].get<double>(), 680.0, 1e-9);
    EXPECT_NEAR(j["final"]["measures"]["ram_y"].get<double>(), y_min, 1e-9);
    EXPECT_EQ(j["final"]["measures"]["ram_v"].get<double>(), 0.0);
  }
  EXPECT_NEAR(t_from[0], t_from[1], 1e-6);
}

TEST(SimulateCli, WiperDriveRunsFreeWithFrictionInEveryPinTheSameInBothForms) {
  // Issue 49's wiper in free motion: a motor torque falling with speed (4 N*m less a rotary
  // damper) against the blade's switched drag and Coulomb friction in every pin. The two forms
  // integrate different equations (dual: v̇ on the chart; primal: the momenta): the same motion,
  // the same events, the balance held with the pins' dissipation booked.
  const std::string loads =
      "loads=[{name: drag_up, type: torque, body: rocker, torque: -1500, active_while: {measure: "
      "rocker_angle, velocity: positive}}, {name: drag_down, type: torque, body: rocker, torque: "
      "1500, active_while: {measure: rocker_angle, velocity: negative}}, {name: motor, type: "
      "torque, body: crank, torque: 4000}, {name: motor_curve, type: rotary-spring-damper, "
      "bodies: [ground, crank], stiffness: 0, damping: 5}]";
  nlohmann::json runs[2];
  int k = 0;
  for (const char* form : {"dual", "primal"}) {
    SCOPED_TRACE(form);
    const auto r =
        run_cli({"simulate", test::bundled_file("wiper-drive"), "--t-end", "3", "--form", form,
                 "--rtol", "1e-10", "--atol", "1e-12", "--set", loads, "--json", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.err.find("does not apply joint friction"), std::string::npos) << r.err;
    runs[k] = nlohmann::json::parse(r.out);
    EXPECT_EQ(runs[k]["status"], "completed");
    EXPECT_EQ(runs[k]["energy"]["balance"], "held");
    EXPECT_GT(runs[k]["friction_switches"].get<long>(), 4);
    ++k;
  }
  EXPECT_EQ(runs[0]["friction_switches"], runs[1]["friction_switches"]);
  EXPECT_EQ(runs[0]["load_switches"], runs[1]["load_switches"]);
  const double crank0 = runs[0]["final"]["measures"]["crank_angle"].get<double>();
  EXPECT_GT(crank0, 720.0) << "two turns at least";
  EXPECT_NEAR(runs[1]["final"]["measures"]["crank_angle"].get<double>(), crank0, 1e-5);
  EXPECT_NEAR(runs[1]["final"]["work"].get<double>(), runs[0]["final"]["work"].get<double>(),
              1e-6 * std::abs(runs[0]["final"]["work"].get<double>()));
}

}  // namespace
}  // namespace orthomech

namespace orthomech {
namespace {

TEST(SimulateCli, APinStuckByItsFrictionIsListedAndPrinted) {
  // The pendulum of tests/data/reliability with its switched torques replaced by friction in its
  // pin, enough to hold it near the bottom: it sticks at a turning point and stays stuck.
  const std::vector<std::string> args = {
      "simulate", test::source_path("tests/data/reliability/coulomb-pendulum.yaml"),
      "--t-end",  "10",
      "--set",    "loads=[{name: weight, type: gravity}]",
      "--set",    "joints.O.friction={coefficient: 0.5, radius: 0.3}"};
  std::vector<std::string> json_args = args;
  json_args.insert(json_args.end(), {"--json", "-q"});
  const auto r = run_cli(json_args);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "completed");
  ASSERT_EQ(j["contacts"].size(), 1u) << j["contacts"];
  EXPECT_EQ(j["contacts"][0]["joint"], "O");
  EXPECT_EQ(j["contacts"][0]["stop"], "stuck");
  EXPECT_TRUE(j["contacts"][0]["t_to"].is_null());
  const auto text = run_cli(args);
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("stuck       joint 'O' by its pin friction from t = "), std::string::npos)
      << text.out.substr(0, 800);
}

}  // namespace
}  // namespace orthomech

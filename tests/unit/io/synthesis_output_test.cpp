// The documents of a synthesis result (src/io/synthesis_output.cpp): the JSON and the CSV carry
// the result's numbers in the task's units (lengths in mm, the drive in N*mm), one CSV row per
// candidate with as many fields as the header.
#include "orthomech/io/synthesis_output.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace orthomech {
namespace {

std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (const char c : line) {
    if (c == '"') quoted = !quoted;
    if (c == ',' && !quoted)
      out.emplace_back();
    else
      out.back() += c;
  }
  return out;
}

TEST(SynthesisOutput, JsonAndCsvInTheTasksUnits) {
  const synthesis::SynthesisTask task = synthesis::load_synthesis_task(
      std::string(ORTHOMECH_SOURCE_DIR) + "/examples/synthesis-motion.yaml");
  const synthesis::SynthesisResult r = synthesis::run_synthesis(task);
  ASSERT_FALSE(r.accepted.empty());
  const synthesis::SynthesisCandidate& c = r.accepted[0];
  ASSERT_TRUE(c.cycle.has_value());
  const auto& fb = std::get<synthesis::FourBar>(c.linkage);
  const auto j = nlohmann::json::parse(synthesis_json(task, r));
  EXPECT_EQ(j["accepted"].size(), r.accepted.size());
  EXPECT_DOUBLE_EQ(j["accepted"][0]["crank"].get<double>(), fb.a / 1e-3);
  EXPECT_DOUBLE_EQ(j["accepted"][0]["cycle"]["peak_drive"].get<double>(),
                   c.cycle->peak_drive / 1e-3);
  EXPECT_EQ(j["accepted"][0]["cycle"]["drive_unit"], "N*mm");
  std::istringstream csv(synthesis_csv(task, r));
  std::string header, row;
  std::getline(csv, header);
  const std::vector<std::string> names = fields(header);
  size_t rows = 0;
  while (std::getline(csv, row)) {
    ++rows;
    EXPECT_EQ(fields(row).size(), names.size()) << row;
  }
  EXPECT_EQ(rows, r.accepted.size() + r.rejected.size());
  std::getline(std::istringstream(synthesis_csv(task, r)).ignore(1 << 20, '\n'), row);
  const std::vector<std::string> first = fields(row);
  const auto at = [&](const std::string& name) {
    for (size_t k = 0; k < names.size(); ++k)
      if (names[k] == name) return std::stod(first[k]);
    ADD_FAILURE() << name;
    return 0.0;
  };
  EXPECT_DOUBLE_EQ(at("crank"), fb.a / 1e-3);
  EXPECT_DOUBLE_EQ(at("peak_pin_force"), c.cycle->peak_pin_force);
  EXPECT_NE(synthesis_text(task, r).find("crank-rocker"), std::string::npos);
}

}  // namespace
}  // namespace orthomech

// `orthomech synthesize` (cli/synthesize.cpp): exit codes, the JSON document, the files written,
// and that every written candidate is a mechanism file `validate` passes and `cycle` runs.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using test::run_cli;

std::string example(const std::string& name) {
  return std::string(ORTHOMECH_SOURCE_DIR) + "/examples/" + name;
}

// The peaks that rank a candidate (its JSON `cycle` object) are those `cycle --json` prints for
// its written file, to 1e-9 relative.
void expect_peaks_of_cycle(const nlohmann::json& c, const std::string& file) {
  const auto cy = run_cli({"cycle", file, "--json", "-q"});
  ASSERT_EQ(cy.status, 0) << file << ": " << cy.err;
  const auto peaks = nlohmann::json::parse(cy.out)["peaks"];
  EXPECT_NEAR(c["cycle"]["peak_drive"].get<double>(), peaks["drive"]["peak"].get<double>(),
              1e-9 * peaks["drive"]["peak"].get<double>())
      << file;
  const std::string pin = c["cycle"]["peak_pin"].get<std::string>() + ".|F|";
  EXPECT_NEAR(c["cycle"]["peak_pin_force"].get<double>(), peaks[pin]["peak"].get<double>(),
              1e-9 * peaks[pin]["peak"].get<double>())
      << file << " " << pin;
}

TEST(SynthesizeCli, MotionTaskWritesCandidatesThatValidateAndCycle) {
  const std::string dir = ::testing::TempDir() + "/synthesize-motion";
  std::filesystem::remove_all(dir);
  const auto r = run_cli({"synthesize", example("synthesis-motion.yaml"), "--out", dir, "--json",
                          "--report", dir + "/report.html"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/report.html"));
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["kind"], "motion");
  ASSERT_FALSE(j["accepted"].empty());
  EXPECT_TRUE(std::filesystem::exists(dir + "/candidates.csv"));
  for (const auto& c : j["accepted"]) {
    EXPECT_TRUE(c["accepted"].get<bool>());
    const std::string file = dir + "/" + c["name"].get<std::string>() + ".yaml";
    ASSERT_TRUE(std::filesystem::exists(file)) << file;
    EXPECT_EQ(run_cli({"validate", file, "-q"}).status, 0) << file;
    EXPECT_EQ(c["cycle"]["drive_unit"], "N*mm");
    expect_peaks_of_cycle(c, file);
  }
}

// A spatial RSSR task (linkage: rssr): its candidate is a dimension-3 file that `validate` passes
// at the task's transmission bound (20°: index sin 20°) and `cycle` runs with the peaks the JSON
// reports; the CSV has the RSSR's columns.
TEST(SynthesizeCli, RssrTaskWritesASpatialFileThatValidatesAndCycles) {
  const std::string dir = ::testing::TempDir() + "/synthesize-rssr";
  std::filesystem::remove_all(dir);
  const auto r = run_cli({"synthesize", example("synthesis-rssr.yaml"), "--out", dir, "--json",
                          "--report", dir + "/report.html"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["accepted"].size(), 1u);
  const auto& c = j["accepted"][0];
  EXPECT_NEAR(c["coupler"].get<double>(), 420.0, 1e-6);
  EXPECT_EQ(c["output_axis"]["point"], nlohmann::json({300.0, 50.0, 200.0}));
  const std::string file = dir + "/candidate-1.yaml";
  const auto v = run_cli({"validate", file, "-q", "--min-transmission", "20"});
  EXPECT_EQ(v.status, 0) << v.out << v.err;
  expect_peaks_of_cycle(c, file);
  std::FILE* f = std::fopen((dir + "/candidates.csv").c_str(), "r");
  ASSERT_NE(f, nullptr);
  char header[512] = {};
  ASSERT_NE(std::fgets(header, sizeof header, f), nullptr);
  std::fclose(f);
  EXPECT_EQ(std::string(header).rfind("name,accepted,coupler,a_x,a_y,a_z,b_x,b_y,b_z,", 0), 0u)
      << header;
}

// Under mpirun the ranks share the path search's starts (process_share.hpp, ProcessShare; every
// rank gathers every outcome): the JSON document and the candidate files are those of one
// process, for 2 and 3 ranks (the README tour's path task with 40 starts, to keep it short).
TEST(SynthesizeCli, MpirunGivesTheResultOfOneProcess) {
  ASSERT_EQ(std::system("command -v mpirun > /dev/null 2>&1"), 0)
      << "mpirun is not installed: scripts/setup installs Open MPI (openmpi-bin, libopenmpi-dev)";
  const std::string dir = ::testing::TempDir() + "/synthesize-mpi";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string task = dir + "/path.yaml";
  {
    std::string text = test::read_text(example("synthesis-path.yaml"));
    text.replace(text.find("starts: 200"), 11, "starts: 40");
    std::FILE* f = std::fopen(task.c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
  }
  const auto one = run_cli({"synthesize", task, "--json", "-j", "1", "--out", dir + "/one"});
  ASSERT_EQ(one.status, 0) << one.err;
  ASSERT_FALSE(nlohmann::json::parse(one.out)["accepted"].empty());
  for (const char* ranks : {"2", "3"}) {
    SCOPED_TRACE(ranks);
    const std::string out = dir + "/mpi" + ranks;
    const std::string command =
        "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
        "OMPI_MCA_rmaps_base_oversubscribe=1 mpirun -n " +
        std::string(ranks) + " '" + std::string(ORTHOMECH_CLI) + "' synthesize '" + task +
        "' --json -j 1 -v --out '" + out + "' > '" + out + ".json' 2> '" + out + ".log'";
    const int status = std::system(command.c_str());
    const std::string log = test::read_text(out + ".log");
    ASSERT_EQ(status, 0) << log;
    EXPECT_NE(log.find(std::string(ranks) + " MPI ranks share"), std::string::npos) << log;
    EXPECT_EQ(test::read_text(out + ".json"), one.out);
    EXPECT_EQ(test::read_text(out + "/candidate-1.yaml"),
              test::read_text(dir + "/one/candidate-1.yaml"));
    EXPECT_EQ(test::read_text(out + "/candidates.csv"),
              test::read_text(dir + "/one/candidates.csv"));
  }
}

TEST(SynthesizeCli, ExitCodes) {
  const std::string dir = ::testing::TempDir();
  // A mistake in the task: exit 2 at its line.
  const std::string bad = dir + "/bad-task.yaml";
  {
    std::FILE* f = std::fopen(bad.c_str(), "w");
    std::fputs("orthomech-synthesis: 1\ntask: motion\nposes: [[0, 0, 0], [1, 0, 0]]\n", f);
    std::fclose(f);
  }
  const auto b = run_cli({"synthesize", bad});
  EXPECT_EQ(b.status, 2);
  EXPECT_NE(b.err.find("bad-task.yaml:3:"), std::string::npos) << b.err;
  // Every candidate rejected (a transmission bound the only four-bar misses): exit 1, listed.
  // The pairs: mechanisms/crank-rocker.yaml's rocker angle at crank 60°, 150°, 270° (closed
  // form, as in synthesis/synthesize_test.cpp); its worst transmission angle over that motion is
  // 48.99°, below the 60° asked.
  const std::string strict = dir + "/strict-task.yaml";
  {
    std::FILE* f = std::fopen(strict.c_str(), "w");
    std::fputs(
        "orthomech-synthesis: 1\ntask: function\nground: 70\n"
        "pairs: [[60, 71.797553609615], [150, 115.823166144399], [270, 132.362157995438]]\n"
        "require: {min_transmission: 60}\n",
        f);
    std::fclose(f);
  }
  const auto s = run_cli({"synthesize", strict});
  EXPECT_EQ(s.status, 1) << s.err;
  EXPECT_NE(s.out.find("rejected: "), std::string::npos) << s.out;
}

}  // namespace
}  // namespace orthomech

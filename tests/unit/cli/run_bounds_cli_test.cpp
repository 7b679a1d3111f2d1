// The command line's side of a bounded run (cli/run_bounds.hpp, issue 47): the time limit stops
// a long motion with exit 5, the progress line appears on stderr (and not with -q), SIGINT and
// SIGTERM stop a run cleanly with what it computed, marked incomplete.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using test::run_cli;

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(RunBoundsCli, TimeLimitStopsALongRun) {
  const auto r = run_cli({"simulate", test::bundled_file("n-four-bar-40"), "--t-end", "10000",
                          "--time-limit", "0.5", "--json", "-q"});
  EXPECT_EQ(r.status, 5) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["stop"], "time_limit");
  EXPECT_FALSE(j["complete"].get<bool>());
}

TEST(RunBoundsCli, ProgressLineOnStderr) {
  ::setenv("ORTHOMECH_PROGRESS", "1", 1);
  const auto r = run_cli(
      {"simulate", test::bundled_file("n-four-bar-40"), "--t-end", "10000", "--time-limit", "1.2"});
  ::unsetenv("ORTHOMECH_PROGRESS");
  EXPECT_EQ(r.status, 5) << r.err;
  EXPECT_TRUE(has(r.err, "simulate: 0 %")) << r.err;
  // -q: no progress.
  ::setenv("ORTHOMECH_PROGRESS", "1", 1);
  const auto quiet = run_cli({"simulate", test::bundled_file("n-four-bar-40"), "--t-end", "10000",
                              "--time-limit", "0.6", "-q"});
  ::unsetenv("ORTHOMECH_PROGRESS");
  EXPECT_FALSE(has(quiet.err, "simulate: 0 %")) << quiet.err;
}

// Runs the CLI with stdout to `out` and stderr to `err`, with ORTHOMECH_PROGRESS=1 so that the
// run's first progress line ("simulate: 0 %") says it has started; sends `signal` once that line
// is there (within 120 s) and `after` later; the exit status (or −1 when a signal ended the
// process).
int run_and_signal(const std::vector<std::string>& args, int signal, const std::string& out,
                   const std::string& err,
                   std::chrono::milliseconds after = std::chrono::milliseconds(200)) {
  // No stale progress line of an earlier run may be taken for this one's start.
  std::remove(err.c_str());
  std::remove(out.c_str());
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<char*> argv;
    std::string cli = ORTHOMECH_CLI;
    argv.push_back(cli.data());
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::setenv("ORTHOMECH_PROGRESS", "1", 1);
    if (!std::freopen(out.c_str(), "w", stdout)) std::_Exit(99);
    if (!std::freopen(err.c_str(), "w", stderr)) std::_Exit(99);
    ::execv(cli.c_str(), argv.data());
    std::_Exit(98);
  }
  const auto start = std::chrono::steady_clock::now();
  const std::string started = args.front() + ": ";
  while (!has(test::read_text(err), started) &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(120))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(after);  // a few steps into the run
  ::kill(pid, signal);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(RunBoundsCli, SigtermStopsCleanlyAndWritesWhatWasComputed) {
  test::TempDir dir("orthomech_rel_");
  const std::string out = (dir.path / "out.json").string(), err = (dir.path / "err.txt").string();
  for (const int signal : {SIGTERM, SIGINT}) {
    SCOPED_TRACE(signal);
    const int status = run_and_signal(
        {"simulate", test::bundled_file("n-four-bar-40"), "--t-end", "10000", "--json"}, signal,
        out, err);
    EXPECT_EQ(status, 5) << test::read_text(err);
    const auto j = nlohmann::json::parse(test::read_text(out));
    EXPECT_EQ(j["stop"], "interrupted");
    EXPECT_FALSE(j["complete"].get<bool>());
    EXPECT_GT(j["samples"]["t"].size(), 0u);
  }
}

// crosscheck: the time limit and the step budget stop it with exit 5, its JSON marked incomplete.
TEST(RunBoundsCli, CrosscheckStopsAtItsBounds) {
  const auto r = run_cli({"crosscheck", test::bundled_file("n-four-bar-40"), "--t-end", "1000",
                          "--time-limit", "0.5", "--json", "-q"});
  EXPECT_EQ(r.status, 5) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["stop"], "time_limit");
  EXPECT_FALSE(j["complete"].get<bool>());
  EXPECT_FALSE(j["pass"].get<bool>());
  const auto b = run_cli(
      {"crosscheck", test::bundled_file("crank-rocker"), "--max-steps", "5", "--json", "-q"});
  EXPECT_EQ(b.status, 5) << b.err;
  EXPECT_EQ(nlohmann::json::parse(b.out)["stop"], "budget");
  EXPECT_TRUE(has(b.err, "--max-steps")) << b.err;
}

// cycle: the time limit and SIGINT/SIGTERM stop the sweep with exit 5; the positions swept are
// written, the JSON marked incomplete. The double wishbone at 1e5 positions sweeps for about
// 1.5 s in the Release build (several times longer under the sanitizers).
TEST(RunBoundsCli, CycleStopsAtItsTimeLimitAndOnASignal) {
  const std::vector<std::string> args = {"cycle", test::bundled_file("double-wishbone"), "--steps",
                                         "100000", "--json"};
  std::vector<std::string> limited = args;
  limited.insert(limited.end(), {"--time-limit", "0.2", "-q"});
  const auto r = run_cli(limited);
  EXPECT_EQ(r.status, 5) << r.err;
  EXPECT_TRUE(has(r.err, "the time limit of 0.2 s is reached (--time-limit)")) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "stopped");
  EXPECT_EQ(j["stop"], "time_limit");
  EXPECT_FALSE(j["complete"].get<bool>());
  EXPECT_GT(j["positions"].get<int>(), 1);
  EXPECT_LT(j["positions"].get<int>(), 100000);

  test::TempDir dir("orthomech_rel_");
  const std::string out = (dir.path / "out.json").string(), err = (dir.path / "err.txt").string();
  const int status = run_and_signal(args, SIGINT, out, err, std::chrono::milliseconds(50));
  EXPECT_EQ(status, 5) << test::read_text(err);
  const auto s = nlohmann::json::parse(test::read_text(out));
  EXPECT_EQ(s["stop"], "interrupted");
  EXPECT_FALSE(s["complete"].get<bool>());
  EXPECT_GT(s["positions"].get<int>(), 0);
}

// assemble: the time limit stops Ipopt after its iteration (the sketch needs several): exit 5,
// `status: stopped`, nothing written even with --write; without the limit it assembles.
TEST(RunBoundsCli, AssembleStopsAtItsTimeLimitAndWritesNothing) {
  const std::string sketch =
      std::string(ORTHOMECH_SOURCE_DIR) + "/tests/data/reliability/sketched-crank-rocker.yaml";
  test::TempDir dir("orthomech_rel_");
  const std::string written = (dir.path / "closed.yaml").string();
  const auto r =
      run_cli({"assemble", sketch, "--time-limit", "1e-6", "--write", written, "--json", "-q"});
  EXPECT_EQ(r.status, 5) << r.err;
  EXPECT_TRUE(has(r.err, "the time limit of 1e-06 s is reached (--time-limit)")) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "stopped");
  EXPECT_EQ(j["stop"], "time_limit");
  EXPECT_FALSE(j["complete"].get<bool>());
  EXPECT_TRUE(j["written"].is_null());
  EXPECT_FALSE(std::filesystem::exists(written));
  const auto whole = run_cli({"assemble", sketch, "--write", written, "--json", "-q"});
  EXPECT_EQ(whole.status, 0) << whole.err;
  EXPECT_TRUE(nlohmann::json::parse(whole.out)["complete"].get<bool>());
  EXPECT_TRUE(std::filesystem::exists(written));
}

// validate: the time limit stops the multi-start search (1e5 starts take about 10 s): exit 5,
// the report does not pass and says which checks did not run; with the default starts it passes.
TEST(RunBoundsCli, ValidateStopsAtItsTimeLimitAndDoesNotPass) {
  const std::string file = test::bundled_file("crank-rocker");
  const auto r =
      run_cli({"validate", file, "--starts", "100000", "--time-limit", "0.3", "--json", "-q"});
  EXPECT_EQ(r.status, 5) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["pass"].get<bool>());
  EXPECT_FALSE(j["complete"].get<bool>());
  EXPECT_EQ(j["stop"], "time_limit");
  EXPECT_TRUE(has(j["message"].get<std::string>(), "the checks from position 'p1' on did not run"))
      << j["message"];
  for (const auto& p : j["positions"]) EXPECT_FALSE(p["pass"].get<bool>());
  const auto text = run_cli({"validate", file, "--starts", "100000", "--time-limit", "0.3"});
  EXPECT_EQ(text.status, 5);
  EXPECT_FALSE(has(text.out, "every position passes")) << text.out;
  EXPECT_TRUE(has(text.out, "stopped: ")) << text.out;
  const auto whole = run_cli({"validate", file, "--json", "-q"});
  EXPECT_EQ(whole.status, 0) << whole.err;
  EXPECT_TRUE(nlohmann::json::parse(whole.out)["complete"].get<bool>());
}

}  // namespace
}  // namespace orthomech

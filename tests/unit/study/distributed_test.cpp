// A study shared among MPI ranks (src/study/distributed.cpp): a process is an MPI study exactly
// when a launcher (Open MPI, PMI, PMIx) says it has two or more ranks and the library has MPI. The
// ranks themselves are exercised end to end by SweepCli.MpirunGivesTheFilesOfOneProcess*
// (cli/sweep_cli_test.cpp: mpirun -n 2 and -n 3 write the files of one process).
#include "orthomech/study/distributed.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

namespace orthomech {
namespace {

// Sets (or unsets) the launchers' variables for one scope, restoring them after.
class Environment {
 public:
  Environment() {
    for (const char* v : kVariables) {
      const char* value = std::getenv(v);
      saved_.emplace_back(value ? std::optional<std::string>(value) : std::nullopt);
      ::unsetenv(v);
    }
  }
  ~Environment() {
    for (size_t i = 0; i < saved_.size(); ++i) {
      if (saved_[i])
        ::setenv(kVariables[i], saved_[i]->c_str(), 1);
      else
        ::unsetenv(kVariables[i]);
    }
  }
  Environment(const Environment&) = delete;
  Environment& operator=(const Environment&) = delete;
  static constexpr const char* kVariables[] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"};

 private:
  std::vector<std::optional<std::string>> saved_;
};

TEST(Distributed, NotLaunchedByMpirunIsNotAnMpiStudy) {
  const Environment env;
  EXPECT_FALSE(mpi_launched());
  for (const char* v : Environment::kVariables) {
    ::setenv(v, "1", 1);  // one rank: the study runs in this process alone
    EXPECT_FALSE(mpi_launched()) << v;
    ::unsetenv(v);
  }
}

TEST(Distributed, TwoOrMoreRanksAreAnMpiStudyWhenTheLibraryHasMpi) {
#ifdef ORTHOMECH_TEST_LIBRARY_HAS_MPI
  constexpr bool kHasMpi = true;
#else
  constexpr bool kHasMpi = false;
#endif
  const Environment env;
  for (const char* v : Environment::kVariables) {
    ::setenv(v, "3", 1);
    EXPECT_EQ(mpi_launched(), kHasMpi) << v;
    ::unsetenv(v);
  }
}

}  // namespace
}  // namespace orthomech

#pragma once
// `orthomech cycle FILE --drivers A,B,…`: the several-driver sweep (analysis/multi_drive.hpp);
// part of the `cycle` subcommand (cli/cycle.cpp), its output in this file.
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech::cli {

struct DriversRequest {
  std::vector<std::string> drivers;  // driver (or driven joint) names of the file
  double t_end = 0.0;                // s; 0: one period of the slowest law
  int steps = 0;                     // 0: 101
  bool json = false;
  std::string units = "file";
  std::string out;  // directory for drivers.csv
};

// Runs the sweep and prints its table (or JSON); returns the exit code. Bad requests throw
// CLI::ValidationError (exit 2).
int run_cycle_drivers(const Model& model, const DriversRequest& request);

}  // namespace orthomech::cli

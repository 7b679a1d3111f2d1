// The peak drive of a mechanism over one cycle of its driver, with orthomech as a library:
//   peak_drive [FILE]   (default: the package's crank-rocker.yaml)
// prints "NAME: peak drive VALUE UNIT at input VALUE rad" in SI units, as
// `orthomech cycle FILE --units si --json` reports peaks.drive.
#include <cstdio>
#include <exception>
#include <string>
#include <variant>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/version.hpp"

int main(int argc, char** argv) {
  const std::string file = argc > 1 ? argv[1] : std::string(MECHANISMS_DIR) + "/crank-rocker.yaml";
  try {
    const orthomech::Model model = orthomech::load_mechanism(file);
    // The file's driver, as `orthomech cycle` takes it: analysis.driver, else the first.
    if (model.drivers.empty()) {
      std::fprintf(stderr, "%s has no driver\n", file.c_str());
      return 2;
    }
    orthomech::CycleOptions options;
    options.driver = model.drivers.front();
    for (const orthomech::Driver& d : model.drivers)
      if (d.name == model.analysis.driver) options.driver = d;
    options.steps = model.analysis.steps;
    const orthomech::CycleResult result = orthomech::run_cycle(model, options);
    if (result.status == orthomech::CycleStatus::failed ||
        result.status == orthomech::CycleStatus::invalid_request) {
      std::fprintf(stderr, "%s: %s\n", file.c_str(), result.message.c_str());
      return 3;
    }
    // A driver whose coordinate is an angle (a planar or spatial revolute, a cylindrical's or
    // screw's turn) takes a torque; a slide a force.
    const bool angular = orthomech::joint_coordinate_kind(
                             model.joints[static_cast<std::size_t>(options.driver.joint)]) ==
                         orthomech::CoordinateKind::angle;
    // The drive first, then every reaction magnitude.
    const std::vector<orthomech::SeriesSummary> summary = orthomech::summarize_cycle(
        result, orthomech::reaction_magnitudes(result), angular ? "N*m" : "N");
    const orthomech::SeriesSummary& drive = summary.front();
    std::printf("%s: peak drive %.17g %s at input %.17g %s (orthomech %s)\n", model.name.c_str(),
                drive.peak, drive.unit.c_str(), drive.peak_input, angular ? "rad" : "m",
                orthomech::kVersion);
  } catch (const orthomech::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 4;
  }
  return 0;
}

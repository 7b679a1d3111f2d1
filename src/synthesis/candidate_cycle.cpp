#include "candidate_cycle.hpp"

#include <cmath>
#include <numbers>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace orthomech::synthesis::detail {

namespace {

// The request: the file's only driver, a full cycle or the range of the targets.
CycleOptions cycle_request(const Model& model, const SynthesisCandidate& c, bool full_turn) {
  CycleOptions o;
  o.driver = model.drivers.front();
  o.steps = 360;
  if (!full_turn) {
    o.full_cycle = false;
    o.use_start = true;
    o.start = c.crank_angles.front();
    o.end = c.crank_angles.back();
  }
  return o;
}

// The peaks over the run: the drive (summarize_cycle's first series) and the largest force
// magnitude of a joint (the series in newtons).
CandidateCycle figures(const CycleResult& r, const SynthesisCandidate& c, bool full_turn) {
  CandidateCycle f;
  f.from = c.crank_angles.front();
  f.to = full_turn ? f.from + 2.0 * std::numbers::pi : c.crank_angles.back();
  f.positions = static_cast<int>(r.points.size());
  const std::vector<SeriesSummary> series = summarize_cycle(r, reaction_magnitudes(r), "N*m");
  f.peak_drive = series.front().peak;
  for (size_t k = 1; k < series.size(); ++k)
    if (series[k].unit == "N" && series[k].peak > f.peak_pin_force) {
      f.peak_pin_force = series[k].peak;
      f.peak_pin = series[k].name.substr(0, series[k].name.find('.'));
    }
  return f;
}

}  // namespace

void check_by_cycle(SynthesisCandidate& c, bool full_turn) {
  Model model;
  try {
    model = parse_mechanism(c.file_text, c.name + ".yaml");
  } catch (const InputError& e) {  // check_by_validate has said so already
    return;
  }
  const CycleResult r = run_cycle(model, cycle_request(model, c, full_turn));
  if (r.status != CycleStatus::completed) {
    c.rejections.push_back(std::string("cycle: ") + to_string(r.status) +
                           (r.message.empty() ? "" : ": " + r.message));
    return;
  }
  c.cycle = figures(r, c, full_turn);
}

}  // namespace orthomech::synthesis::detail

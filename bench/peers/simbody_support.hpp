#pragma once
// What the Simbody peers share: the process CPU clock (cpu_clock.hpp), Simbody's version, the
// integrator named on the command line (its accuracy and constraint tolerance both ACC), the timed
// stepping loop with its CPU cap and loop-gap samples, and the one-line reason of a stop.
#include <Simbody.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>

#include "cpu_clock.hpp"

namespace orthomech::peers {

// "major.minor" of the Simbody library linked (3.7 from Debian's libsimbody-dev).
inline std::string simbody_version() {
  int major = 0, minor = 0, build = 0;
  SimTK_version_simbody(&major, &minor, &build);
  return std::to_string(major) + "." + std::to_string(minor);
}

// rkm (Runge–Kutta–Merson), rkf (Runge–Kutta–Feldberg), rk3 or cpodes (CPodes, BDF), with its
// accuracy and its constraint tolerance both set to `accuracy`.
inline std::unique_ptr<SimTK::Integrator> make_integrator(const SimTK::System& system,
                                                          const std::string& method,
                                                          double accuracy) {
  std::unique_ptr<SimTK::Integrator> integ;
  if (method == "rkm")
    integ = std::make_unique<SimTK::RungeKuttaMersonIntegrator>(system);
  else if (method == "rkf")
    integ = std::make_unique<SimTK::RungeKuttaFeldbergIntegrator>(system);
  else if (method == "rk3")
    integ = std::make_unique<SimTK::RungeKutta3Integrator>(system);
  else
    integ = std::make_unique<SimTK::CPodesIntegrator>(system);
  integ->setAccuracy(accuracy);
  integ->setConstraintTolerance(accuracy);
  return integ;
}

// What a timed run reached.
struct SimbodyRun {
  SimTK::State last;  // the last state reached (after a failure: the one before it)
  double cpu = 0.0;   // CPU seconds of the stepTo calls only
  double max_gap = 0.0;
  std::string stop;  // empty, "CPU cap reached" or "integrator failure: " + Simbody's text
};

// Integrates from `start` to t_end with `integ`: TimeStepper::initialize (which projects the
// start onto the constraints at the integrator's constraint tolerance), then stepTo every 0.01 s
// of simulated time, only the stepTo calls timed on the process CPU clock. gap(state) (the
// loop-closure gap, m; the state realized to Stage::Position) is sampled at the start and after
// every interval. Stops early on an integrator exception or once the CPU time exceeds `cap`
// (checked after every interval: a run stuck inside one interval is stopped by the caller's wall
// clock, run_peers.py).
template <class Gap>
SimbodyRun run_timed(const SimTK::MultibodySystem& system, SimTK::Integrator& integ,
                     const SimTK::State& start, double t_end, double cap, const Gap& gap) {
  SimTK::TimeStepper ts(system, integ);
  ts.initialize(start);
  SimbodyRun run;
  run.last = ts.getState();
  system.realize(run.last, SimTK::Stage::Position);
  run.max_gap = gap(run.last);
  const long samples = std::max(1L, std::lround(t_end / 0.01));
  for (long i = 1; i <= samples && run.stop.empty(); ++i) {
    const double c0 = cpu_seconds();
    try {
      ts.stepTo(t_end * static_cast<double>(i) / static_cast<double>(samples));
      run.last = ts.getState();
    } catch (const std::exception& e) {
      run.stop = std::string("integrator failure: ") + e.what();
    }
    run.cpu += cpu_seconds() - c0;
    system.realize(run.last, SimTK::Stage::Position);
    run.max_gap = std::max(run.max_gap, gap(run.last));
    if (run.cpu > cap && run.stop.empty()) run.stop = "CPU cap reached";
  }
  return run;
}

// The output line's note for a stop: "" when the run reached its end; else the whole text on
// stderr and its one-line reason: the last non-empty line (Simbody nests "thrown at FILE:LINE"
// blocks; the innermost reason comes last), or its "Unable to advance time past T." line.
inline std::string stop_note(const std::string& stop) {
  if (stop.empty()) return "";
  std::fprintf(stderr, "%s\n", stop.c_str());
  const size_t end = stop.find_last_not_of(" \n");
  const size_t begin = stop.rfind('\n', end);
  std::string first = stop.substr(begin == std::string::npos ? 0 : begin + 1, end - begin);
  first = first.substr(first.find_first_not_of(' '));
  if (const size_t u = stop.find("Unable to"); u != std::string::npos)
    first = stop.substr(u, stop.find('\n', u) - u);  // "Unable to advance time past 2.68212."
  if (stop.rfind("integrator failure", 0) == 0) first = "integrator failure: " + first;
  return " STOP: " + first;
}

}  // namespace orthomech::peers

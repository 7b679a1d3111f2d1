#include "orthomech/study/study.hpp"

#include <omp.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <boost/random/mersenne_twister.hpp>
#include <boost/random/normal_distribution.hpp>
#include <boost/random/uniform_real_distribution.hpp>
#include <cctype>
#include <charconv>
#include <cmath>
#include <exception>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <variant>

#include "../io/yaml_walk.hpp"
#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/cycle_friction.hpp"
#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/analysis/multi_drive.hpp"
#include "orthomech/analysis/shaking.hpp"
#include "orthomech/analysis/validate.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/render.hpp"
#include "orthomech/io/units.hpp"

namespace orthomech {

namespace {

constexpr long kMaxVariants = 1'000'000'000;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// ---- one variant's metrics ---------------------------------------------------------------------

// A summary's column name from its name in `cycle --json`'s peaks: "shaking force" →
// shaking_force, "drive without friction" → drive_without_friction, "A friction moment" →
// A.friction_moment (a joint's, as A.|F|).
std::string summary_column(const std::string& name) {
  const std::string moment = " friction moment";
  if (name.size() > moment.size() &&
      name.compare(name.size() - moment.size(), moment.size(), moment) == 0)
    return name.substr(0, name.size() - moment.size()) + ".friction_moment";
  std::string column = name;
  std::replace(column.begin(), column.end(), ' ', '_');
  return column;
}

// The shaking force and moment of the cycle (about the world origin, as `cycle`'s default):
// shaking_force.peak, .rms, shaking_moment.peak, .rms; with pin friction in the file, as
// `cycle`'s friction: friction.efficiency, friction.dissipated (the energy over the sweep) and
// the peak and RMS of drive_without_friction, J.friction_moment, friction_power.
void shaking_and_friction_metrics(const Model& model, const CycleResult& c, int driver_joint,
                                  bool angular, std::vector<std::pair<std::string, double>>& out) {
  const UnitSystem U = unit_system(model.units);
  const auto add = [&](const SeriesSummary& s, Dimension d) {
    const OutputUnit u = output_unit(d, U);
    const std::string name = summary_column(s.name);
    out.emplace_back(name + ".peak", s.samples > 0 ? u.from_si(s.peak) : kNaN);
    out.emplace_back(name + ".rms", s.samples > 0 ? u.from_si(s.rms) : kNaN);
  };
  const ShakingSeries shaking = shaking_series(model, c, Vec3::Zero());
  for (const SeriesSummary& s : summarize_shaking(model, c, shaking).magnitudes)
    add(s, dimension_of(s.unit));
  const FrictionSeries f = friction_series(model, c, driver_joint,
                                           c.status == CycleStatus::completed && c.reversals == 0);
  if (f.pins.empty()) return;
  out.emplace_back("friction.efficiency", std::isfinite(f.efficiency) ? f.efficiency : kNaN);
  out.emplace_back("friction.dissipated", output_unit(Dimension::moment, U).from_si(f.dissipated));
  for (const SeriesSummary& s : summarize_friction(model, c, f, angular ? "N*m" : "N"))
    add(s, s.name == "drive without friction" ? (angular ? Dimension::moment : Dimension::force)
                                              : dimension_of(s.unit));
}

// The cycle's summary in the file's units, named as in `cycle --json` (peaks.drive.max →
// drive.max; peaks."A.|F|".peak → A.|F|.peak; power.mean; the worst transmission angle of the
// four-bar loops, the worst pressure angle of the slider-crank loops; the dead points).
void cycle_metrics(const Model& model, const CycleResult& c, int driver_joint,
                   std::vector<std::pair<std::string, double>>& out) {
  const UnitSystem U = unit_system(model.units);
  const bool angular = joint_coordinate_kind(model.joints[static_cast<size_t>(driver_joint)]) ==
                       CoordinateKind::angle;
  const std::vector<ReactionMagnitude> magnitudes = reaction_magnitudes(c);
  const std::vector<SeriesSummary> summary = summarize_cycle(c, magnitudes, angular ? "N*m" : "N");
  for (const SeriesSummary& s : summary) {
    const OutputUnit u = output_unit(
        s.name == "drive" ? (angular ? Dimension::moment : Dimension::force) : dimension_of(s.unit),
        U);
    const auto value = [&](double v) { return s.samples > 0 ? u.from_si(v) : kNaN; };
    if (s.name == "drive") {
      out.emplace_back("drive.max", value(s.max.value));
      out.emplace_back("drive.min", value(s.min.value));
      out.emplace_back("drive.peak", value(s.peak));
      out.emplace_back("drive.rms", value(s.rms));
    } else {
      out.emplace_back(s.name + ".peak", value(s.peak));
    }
  }
  CycleMetricsOptions mo;
  mo.driver_joint = driver_joint;
  const CycleMetrics m = compute_cycle_metrics(model, c, mo);
  const OutputUnit power = output_unit(Dimension::power, U);
  out.emplace_back("power.mean", m.power.available ? power.from_si(m.power.mean) : kNaN);
  out.emplace_back("power.peak", m.power.available ? power.from_si(m.power.peak) : kNaN);
  const OutputUnit angle = output_unit(Dimension::angle, U);
  double transmission = kNaN, pressure = kNaN;
  for (const LoopAngleMetric& l : m.loops) {
    const double w = angle.from_si(l.worst.value);
    if (l.slider_crank)
      pressure = std::isnan(pressure) ? w : std::max(pressure, w);
    else
      transmission = std::isnan(transmission) ? w : std::min(transmission, w);
  }
  bool four_bar = false, slider = false;
  for (const LoopAngleMetric& l : m.loops) (l.slider_crank ? slider : four_bar) = true;
  if (four_bar) out.emplace_back("transmission.min", transmission);
  if (slider) out.emplace_back("pressure.max", pressure);
  out.emplace_back("dead_points", static_cast<double>(c.dead_points.size()));
  shaking_and_friction_metrics(model, c, driver_joint, angular, out);
  measure_metrics(model, c, m, driver_joint, out);
}

// The study's expressions over the columns so far, each a column in turn (NaN where one cannot
// be evaluated: the study file's check evaluated them on the nominal design).
void expression_metrics(const std::vector<MetricExpression>& expressions, const UnitSystem& units,
                        std::vector<std::pair<std::string, double>>& out) {
  for (const MetricExpression& e : expressions) {
    double v = kNaN;
    try {
      v = evaluate_metric_expression(e.text, out, &units);
    } catch (const std::invalid_argument&) {
      v = kNaN;
    }
    out.emplace_back(e.name, std::isfinite(v) ? v : kNaN);
  }
}

double flag(bool pass) { return pass ? 1.0 : 0.0; }

// `validate`'s checks (analysis/validate.hpp, default ValidateOptions as `orthomech validate`):
// 1 passes, 0 fails, NaN not checked. The columns depend only on the file's structure (its
// design positions, targets and loops), so that every variant has the nominal design's columns:
//   validate.pass                 the report passes (every position, no defect)
//   validate.order/circuit/branch no order (positions ≥ 2 on one input) / circuit / branch defect
//                                 (NaN when not traced: a position that does not assemble)
//   validate.P.assembles          position P assembles
//   validate.P.target             its target is met (positions with a target)
//   validate.P.change_point       σ_min ≥ min_sigma (not at a change point)
//   validate.P.dof                the inputs fix the position (DOF ≤ inputs)
//   validate.P.dead_point         η ≥ min_sigma (not at a dead point of the inputs)
//   validate.P.transmission       every four-bar loop's transmission angle within the bounds (a
//                                 spatial mechanism: every spatial loop's Sutherland–Roth index)
//   validate.P.pressure           every slider-crank loop's pressure angle within the bound
void validate_metrics(const Model& model, std::vector<std::pair<std::string, double>>& out) {
  const ValidateOptions options;
  const ValidationReport rep = validate_design_positions(model, options);
  const bool four_bars = !find_four_bar_loops(model, -1).empty();
  const bool slider_cranks = !find_slider_crank_loops(model).empty();
  const bool spatial_loops =
      std::any_of(rep.positions.begin(), rep.positions.end(),
                  [](const PositionReport& p) { return !p.spatial_loops.empty(); });
  out.emplace_back("validate.pass", flag(rep.pass()));
  const bool ordered = !rep.input.empty() && model.design_positions.size() >= 2;
  out.emplace_back("validate.order", ordered ? flag(!rep.order_defect) : kNaN);
  out.emplace_back("validate.circuit", rep.circuits > 0 ? flag(!rep.circuit_defect) : kNaN);
  out.emplace_back("validate.branch", rep.circuits > 0 ? flag(!rep.branch_defect) : kNaN);
  for (size_t k = 0; k < model.design_positions.size(); ++k) {
    const DesignPosition& dp = model.design_positions[k];
    const PositionReport& p = rep.positions.at(k);
    const std::string prefix = "validate." + dp.name + ".";
    const bool a = p.assembles;
    const size_t inputs = dp.inputs.size();
    out.emplace_back(prefix + "assembles", flag(a));
    if (dp.target) out.emplace_back(prefix + "target", a ? flag(p.target_met) : kNaN);
    out.emplace_back(prefix + "change_point",
                     a ? flag(p.singular.sigma_min >= options.min_sigma) : kNaN);
    out.emplace_back(prefix + "dof", a ? flag(p.dof <= static_cast<int>(inputs)) : kNaN);
    const bool eta = a && p.dof <= static_cast<int>(inputs) && p.singular.eta.has_value();
    out.emplace_back(prefix + "dead_point",
                     eta ? flag(*p.singular.eta >= options.min_sigma) : kNaN);
    const auto all_ok = [](const auto& loops) {
      return std::all_of(loops.begin(), loops.end(), [](const auto& l) { return l.ok; });
    };
    if (four_bars || spatial_loops)
      out.emplace_back(prefix + "transmission",
                       a ? flag(all_ok(p.four_bars) && all_ok(p.spatial_loops)) : kNaN);
    if (slider_cranks)
      out.emplace_back(prefix + "pressure", a ? flag(all_ok(p.slider_cranks)) : kNaN);
  }
}

// `assemble`'s outcome for the design pose (analysis/assembly.hpp, default AssemblyOptions as
// `orthomech assemble FILE`: no locks, the joint limits kept): assemble.ok 1 when it assembled
// (or was closed already), assemble.distance the mass-metric distance √((q − q₀)ᵀ M (q − q₀))
// from the drawn pose in √(mass unit)·(length unit) of the file (NaN when it did not assemble).
void assemble_metrics(const Model& model, std::vector<std::pair<std::string, double>>& out) {
  const UnitSystem U = unit_system(model.units);
  const AssemblyResult a = assemble(model, model.design_q());
  const bool ok = a.status == AssemblyStatus::assembled || a.status == AssemblyStatus::unchanged;
  out.emplace_back("assemble.ok", flag(ok));
  out.emplace_back("assemble.distance",
                   ok ? a.distance / (std::sqrt(U.mass_si) * U.length_si) : kNaN);
}

// The traced paths of a cycle: the world position of each point at each position (m; z = 0 for
// a planar mechanism).
struct Paths {
  std::vector<double> input;
  std::vector<std::vector<double>> x, y, z;
};
Paths cycle_paths(const Model& model, const CycleResult& c, const std::vector<std::string>& names) {
  const TracePoints points = resolve_trace_points(model, names);
  if (points.status == TraceStatus::bad_request) throw std::invalid_argument(points.message);
  std::vector<VecX> q;
  Paths p;
  for (const DrivenPointView v : c.points) {
    q.emplace_back(v.q);
    p.input.push_back(v.input);
  }
  for (const PointTrace& t : trace_paths(model, points, q, p.input)) {
    p.x.emplace_back();
    p.y.emplace_back();
    p.z.emplace_back();
    for (size_t k = 0; k < t.path.size(); ++k) {
      const Vec3 r = t.at(k);
      p.x.back().push_back(r.x());
      p.y.back().push_back(r.y());
      p.z.back().push_back(r.z());
    }
  }
  return p;
}

// The variant's inputs are the nominal's first positions (the same grid, to rounding; for a
// revolute input, up to whole turns: a cycle started elsewhere may reach the start a turn on).
bool same_inputs(const std::vector<double>& variant, const std::vector<double>& nominal,
                 bool angular) {
  if (variant.empty() || variant.size() > nominal.size()) return false;
  const double turn = 2.0 * std::numbers::pi;
  const double offset = angular ? turn * std::round((variant[0] - nominal[0]) / turn) : 0.0;
  for (size_t k = 0; k < variant.size(); ++k)
    if (std::abs(variant[k] - offset - nominal[k]) > 1e-9 * (1.0 + std::abs(nominal[k])))
      return false;
  return true;
}

// Deviation of each traced point's path from the nominal design's, at the same inputs s_k:
//   e_k = |P(s_k) − P_nominal(s_k)| (in space for a spatial mechanism),  deviation.P.max = max_k
//   e_k, deviation.P.rms = √(Σ_k e_k² / m) (S1)
// over the m positions of the nominal's grid that the variant's cycle reached (all of them when
// it completed), in the file's length unit. The variant's own cycle is used when its inputs are
// the nominal's (a revolute's up to whole turns); else (its design position has another input) a
// constant-speed driver is swept again from the nominal's start input (run_cycle's use_start:
// reached along the branch); NaN when the grids still differ (e.g. a harmonic law changed).
void deviation_metrics(const Model& model, const CycleResult& c, const CycleOptions& options,
                       const NominalPaths& nominal, const std::vector<std::string>& names,
                       std::vector<std::pair<std::string, double>>& out) {
  const double length = unit_system(model.units).length_si;
  const bool angular =
      joint_coordinate_kind(model.joints[static_cast<size_t>(options.driver.joint)]) ==
      CoordinateKind::angle;
  std::vector<double> max(names.size(), kNaN), rms(names.size(), kNaN);
  if (nominal.available && !c.points.empty()) {
    Paths p = cycle_paths(model, c, names);
    if (!same_inputs(p.input, nominal.input, angular) &&
        options.driver.profile == Profile::constant_speed) {
      CycleOptions again = options;
      again.use_start = true;
      again.start = nominal.input.front();
      const CycleResult c2 = run_cycle(model, again);
      p = c2.points.empty() ? Paths{} : cycle_paths(model, c2, names);
    }
    if (same_inputs(p.input, nominal.input, angular)) {
      for (size_t j = 0; j < names.size(); ++j) {
        double e_max = 0.0, e2 = 0.0;
        for (size_t k = 0; k < p.input.size(); ++k) {
          const double e = std::hypot(p.x[j][k] - nominal.x[j][k], p.y[j][k] - nominal.y[j][k],
                                      p.z[j][k] - nominal.z[j][k]);
          e_max = std::max(e_max, e);
          e2 += e * e;
        }
        max[j] = e_max / length;                                                // (S1)
        rms[j] = std::sqrt(e2 / static_cast<double>(p.input.size())) / length;  // (S1)
      }
    }
  }
  for (size_t j = 0; j < names.size(); ++j) {
    out.emplace_back("deviation." + names[j] + ".max", max[j]);
    out.emplace_back("deviation." + names[j] + ".rms", rms[j]);
  }
}

// The several drivers' sweep of a study (Study::drivers): the drivers found by name (those the
// model has), t_end and the steps (0: run_multi_drive's default).
MultiDriveOptions study_multi_drive_options(const Model& model, const Study& study) {
  MultiDriveOptions mo;
  for (const std::string& name : study.drivers)
    for (const Driver& d : model.drivers)
      if (d.name == name) mo.drivers.push_back(d);
  mo.t_end = study.t_end;
  if (study.steps > 0) mo.steps = study.steps;
  return mo;
}

// A variant swept by several drivers (Study::drivers; run_multi_drive, as `cycle --drivers`): its
// status, message and positions, and its metrics — per driver D drive.D.max, drive.D.min,
// drive.D.peak, drive.D.rms; per joint J.|F|.peak (and J.|M|.peak) as the one-driver cycle's;
// every measure's columns over time (multi_drive_measure_metrics).
void multi_drive_variant(const Model& model, const Study& study, VariantResult& r) {
  const MultiDriveOptions mo = study_multi_drive_options(model, study);
  if (mo.drivers.size() != study.drivers.size()) {
    r.status = "invalid";
    r.message = "the variant has not every driver of the study";
    return;
  }
  const MultiDriveResult m = run_multi_drive(model, mo);
  r.status = m.status == MultiDriveStatus::completed         ? "completed"
             : m.status == MultiDriveStatus::stopped         ? "stopped_at_dead_point"
             : m.status == MultiDriveStatus::invalid_request ? "invalid"
                                                             : "failed";
  r.message = m.message;
  r.positions = static_cast<long>(m.points.size());
  if (m.points.empty()) return;
  const UnitSystem U = unit_system(model.units);
  for (size_t i = 0; i < mo.drivers.size(); ++i) {
    const bool angular =
        joint_coordinate_kind(model.joints[static_cast<size_t>(mo.drivers[i].joint)]) ==
        CoordinateKind::angle;
    const OutputUnit u = output_unit(angular ? Dimension::moment : Dimension::force, U);
    double lo = kInf, hi = -kInf, squares = 0.0;
    for (const MultiDrivenPoint& p : m.points) {
      const double v = u.from_si(p.drives(static_cast<Eigen::Index>(i)));
      lo = std::min(lo, v);
      hi = std::max(hi, v);
      squares += v * v;
    }
    const std::string name = "drive." + mo.drivers[i].name;
    r.metrics.emplace_back(name + ".max", hi);
    r.metrics.emplace_back(name + ".min", lo);
    r.metrics.emplace_back(name + ".peak", std::max(std::abs(lo), std::abs(hi)));
    r.metrics.emplace_back(name + ".rms",
                           std::sqrt(squares / static_cast<double>(m.points.size())));
  }
  // The joints' magnitudes, grouped as the one-driver cycle groups them.
  CycleResult shape;
  shape.components = m.components;
  shape.determinate = m.determinate;
  for (const ReactionMagnitude& g : reaction_magnitudes(shape)) {
    const OutputUnit u = output_unit(dimension_of(g.unit), U);
    double peak = 0.0;
    for (const MultiDrivenPoint& p : m.points) {
      double s = 0.0;
      for (const int c : g.components)
        s += p.reactions[static_cast<size_t>(c)] * p.reactions[static_cast<size_t>(c)];
      peak = std::max(peak, std::sqrt(s));
    }
    r.metrics.emplace_back(g.name + ".peak", u.from_si(peak));
  }
  multi_drive_measure_metrics(model, m, r.metrics);
}

CycleOptions study_cycle_options(const Model& model, const Driver& driver, const Study& study) {
  CycleOptions co;
  co.driver = driver;
  co.steps = study.steps > 0 ? study.steps : model.analysis.steps;
  return co;
}

}  // namespace

long variant_count(const Study& study) {
  if (study.kind == StudyKind::monte_carlo) return study.samples;
  if (study.kind == StudyKind::optimize) return study.goal.evaluations;
  double count = 1.0;
  for (const StudyParameter& p : study.parameters) count *= static_cast<double>(p.values.size());
  return count > double(kMaxVariants) ? kMaxVariants + 1 : static_cast<long>(count);
}

std::vector<double> variant_values(const Study& study, long index) {
  std::vector<double> values(study.parameters.size());
  if (study.kind == StudyKind::optimize) {  // the start (the optimiser chooses the others)
    for (size_t j = 0; j < study.parameters.size(); ++j) values[j] = study.parameters[j].mean;
    return values;
  }
  if (study.kind == StudyKind::grid) {
    long rest = index;
    for (size_t j = study.parameters.size(); j-- > 0;) {
      const auto& v = study.parameters[j].values;
      const long n = static_cast<long>(v.size());
      values[j] = v[static_cast<size_t>(rest % n)];
      rest /= n;
    }
    return values;
  }
  boost::random::mt19937_64 engine(
      splitmix64(study.seed ^ splitmix64(static_cast<std::uint64_t>(index))));
  for (size_t j = 0; j < study.parameters.size(); ++j) {
    const StudyParameter& p = study.parameters[j];
    if (p.law == StudyParameter::Law::normal) {
      values[j] = p.sigma > 0.0
                      ? boost::random::normal_distribution<double>(p.mean, p.sigma)(engine)
                      : p.mean;
    } else {
      values[j] = p.tolerance > 0.0 ? boost::random::uniform_real_distribution<double>(
                                          p.mean - p.tolerance, p.mean + p.tolerance)(engine)
                                    : p.mean;
    }
  }
  return values;
}

std::string value_text(double value) {
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return ec == std::errc() ? std::string(buffer, end) : std::string("nan");
}

NominalPaths nominal_paths(const std::string& mechanism, const std::string& origin,
                           const Study& study) {
  NominalPaths n;
  try {
    const Model model = parse_mechanism(mechanism, origin, {});
    const Driver* driver = study_driver(model);
    if (!driver) {
      n.message = "the mechanism has no driver to sweep";
      return n;
    }
    const CycleResult c = run_cycle(model, study_cycle_options(model, *driver, study));
    n.message = c.message;
    if (c.points.empty()) return n;
    Paths p = cycle_paths(model, c, study.metrics.deviation);
    n.input = std::move(p.input);
    n.x = std::move(p.x);
    n.y = std::move(p.y);
    n.z = std::move(p.z);
    n.available = true;
  } catch (const std::exception& e) {
    n.available = false;
    n.message = e.what();
  }
  return n;
}

void attach_nominal_paths(Study& study, const std::string& mechanism, const std::string& origin) {
  if (study.metrics.deviation.empty()) return;
  study.nominal = std::make_shared<const NominalPaths>(nominal_paths(mechanism, origin, study));
}

const Driver* study_driver(const Model& model) {
  for (const Driver& d : model.drivers)
    if (d.name == model.analysis.driver) return &d;
  return model.drivers.empty() ? nullptr : &model.drivers.front();
}

std::vector<FileChange> variant_changes(const Study& study, const std::vector<double>& values) {
  if (values.size() != study.parameters.size())
    throw std::invalid_argument(
        "a variant needs a value per parameter: " + std::to_string(values.size()) + " values for " +
        std::to_string(study.parameters.size()) + " parameters");
  std::vector<FileChange> changes;
  for (size_t j = 0; j < study.parameters.size(); ++j)
    changes.push_back({study.parameters[j].path, value_text(values[j])});
  return changes;
}

VariantResult evaluate_variant(const std::string& mechanism, const std::string& origin,
                               const Study& study, long index, const std::vector<double>& values) {
  VariantResult r;
  r.index = index;
  r.values = values;
  const StudyMetrics& want = study.metrics;
  try {
    const std::vector<FileChange> changes = variant_changes(study, values);
    Model model;
    try {
      model = parse_mechanism(mechanism, origin, changes);
    } catch (const InputError& e) {
      r.status = "invalid";
      r.message = e.what();
      return r;
    }
    r.status = "completed";
    // Several drivers: the sweep over time and its summary (the reader refused deviations).
    if (want.cycle && !study.drivers.empty()) {
      multi_drive_variant(model, study, r);
      if (r.status == "invalid") return r;
    } else if (want.cycle || !want.deviation.empty()) {  // the cycle block and the deviations
      const Driver* driver = study_driver(model);
      if (!driver) {
        r.status = "invalid";
        r.message = "the mechanism has no driver to sweep";
        return r;
      }
      const CycleOptions co = study_cycle_options(model, *driver, study);
      const CycleResult c = run_cycle(model, co);
      // The names of `cycle --json`'s status (docs/cli.md), one word each.
      r.status = c.status == CycleStatus::completed               ? "completed"
                 : c.status == CycleStatus::stopped_at_dead_point ? "stopped_at_dead_point"
                 : c.status == CycleStatus::invalid_request       ? "invalid"
                                                                  : "failed";
      r.message = c.message;
      r.positions = static_cast<long>(c.points.size());
      if (want.cycle && !c.points.empty()) {
        cycle_metrics(model, c, driver->joint, r.metrics);
        measure_at_metrics(model, c, driver->joint, want.at, r.metrics);
      }
      if (!want.deviation.empty()) {
        const std::shared_ptr<const NominalPaths> nominal =
            study.nominal
                ? study.nominal
                : std::make_shared<const NominalPaths>(nominal_paths(mechanism, origin, study));
        deviation_metrics(model, c, co, *nominal, want.deviation, r.metrics);
      }
    }
    if (want.assemble) assemble_metrics(model, r.metrics);
    if (want.validate) validate_metrics(model, r.metrics);
    if (!r.metrics.empty())
      expression_metrics(want.expressions, unit_system(model.units), r.metrics);
  } catch (const std::exception& e) {
    r.status = "failed";
    r.message = std::string("internal error: ") + e.what();
    r.metrics.clear();
  }
  return r;
}

namespace {

// variant_cycle of a study with several drivers: over time, each driver's drive and the measures.
VariantCycle multi_drive_cycle(const Model& model, const Study& study, VariantCycle& v) {
  const MultiDriveOptions mo = study_multi_drive_options(model, study);
  const MultiDriveResult m = run_multi_drive(model, mo);
  v.status = m.status == MultiDriveStatus::completed ? "completed" : "failed";
  v.message = m.message;
  const UnitSystem U = unit_system(model.units);
  const OutputUnit time = output_unit(Dimension::time, U);
  v.input_label = "time [" + time.name + "]";
  std::vector<OutputUnit> units;
  for (const Driver& d : mo.drivers) {
    const bool angular =
        joint_coordinate_kind(model.joints[static_cast<size_t>(d.joint)]) == CoordinateKind::angle;
    units.push_back(output_unit(angular ? Dimension::moment : Dimension::force, U));
    v.series.push_back({"drive." + d.name, units.back().name, {}});
  }
  for (const Measure& meas : model.measures) {
    units.push_back(output_unit(dimension_of(meas.unit), U));
    v.series.push_back({meas.name, units.back().name, {}});
  }
  for (const MultiDrivenPoint& p : m.points) {
    v.input.push_back(time.from_si(p.time));
    size_t k = 0;
    for (Eigen::Index i = 0; i < p.drives.size(); ++i, ++k)
      v.series[k].values.push_back(units[k].from_si(p.drives(i)));
    for (const double y : p.measures) {
      v.series[k].values.push_back(units[k].from_si(y));
      ++k;
    }
  }
  return v;
}

}  // namespace

VariantCycle variant_cycle(const std::string& mechanism, const std::string& origin,
                           const Study& study, long index, const std::vector<double>& values) {
  VariantCycle v;
  v.variant = index;
  Model model;
  try {
    model = parse_mechanism(mechanism, origin, variant_changes(study, values));
  } catch (const InputError& e) {
    v.status = "invalid";
    v.message = e.what();
    return v;
  }
  if (!study.drivers.empty()) return multi_drive_cycle(model, study, v);
  const Driver* driver = study_driver(model);
  if (!driver) {
    v.status = "invalid";
    v.message = "the mechanism has no driver to sweep";
    return v;
  }
  const CycleResult c = run_cycle(model, study_cycle_options(model, *driver, study));
  v.status = c.status == CycleStatus::completed ? "completed" : "failed";
  v.message = c.message;
  const UnitSystem U = unit_system(model.units);
  const Joint& joint = model.joints[static_cast<size_t>(driver->joint)];
  const bool angular = joint_coordinate_kind(joint) == CoordinateKind::angle;
  const OutputUnit in = output_unit(angular ? Dimension::angle : Dimension::length, U);
  const OutputUnit drive = output_unit(angular ? Dimension::moment : Dimension::force, U);
  v.input_label = "input " + joint.name + " [" + in.name + "]";
  v.series.push_back({"drive", drive.name, {}});
  std::vector<OutputUnit> units;
  for (const Measure& m : model.measures) {
    units.push_back(output_unit(dimension_of(m.unit), U));
    v.series.push_back({m.name, units.back().name, {}});
  }
  for (const DrivenPointView p : c.points) {
    v.input.push_back(in.from_si(p.input));
    v.series[0].values.push_back(drive_reported(p) ? drive.from_si(p.drive) : kNaN);
    for (size_t i = 0; i < model.measures.size(); ++i)
      v.series[i + 1].values.push_back(
          measure_reported(model, p, i) ? units[i].from_si(p.measures[i]) : kNaN);
  }
  return v;
}

void run_variants(const std::string& mechanism, const std::string& origin, const Study& study,
                  const std::vector<long>& pending, int jobs,
                  const std::function<void(const VariantResult&)>& done) {
  std::exception_ptr failure;
  const long n = static_cast<long>(pending.size());
  const int threads = jobs > 0 ? jobs : omp_get_max_threads();  // 0: every core
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) if (threads != 1)
  for (long k = 0; k < n; ++k) {
    bool stop = false;
#pragma omp critical(orthomech_study)
    stop = static_cast<bool>(failure);
    if (stop) continue;
    const long index = pending[static_cast<size_t>(k)];
    const VariantResult r =
        evaluate_variant(mechanism, origin, study, index, variant_values(study, index));
#pragma omp critical(orthomech_study)
    {
      if (!failure) {
        try {
          done(r);
        } catch (...) {
          failure = std::current_exception();
        }
      }
    }
  }
  if (failure) std::rethrow_exception(failure);
}

MetricStatistics metric_statistics(const std::string& name,
                                   const std::vector<std::vector<double>>& values,
                                   const std::vector<double>& metric) {
  MetricStatistics s;
  s.metric = name;
  std::vector<size_t> rows;
  for (size_t k = 0; k < metric.size(); ++k)
    if (!std::isnan(metric[k])) rows.push_back(k);
  s.n = static_cast<long>(rows.size());
  const size_t p = values.empty() ? 0 : values.front().size();
  s.sensitivity.assign(p, std::nullopt);
  if (rows.empty()) return s;
  std::vector<double> y;
  y.reserve(rows.size());
  for (size_t k : rows) y.push_back(metric[k]);
  double sum = 0.0;
  for (double v : y) sum += v;
  s.mean = sum / double(y.size());
  double ss = 0.0;
  for (double v : y) ss += (v - s.mean) * (v - s.mean);
  s.stddev = y.size() > 1 ? std::sqrt(ss / double(y.size() - 1)) : 0.0;
  std::vector<double> sorted = y;
  std::sort(sorted.begin(), sorted.end());
  const auto quantile = [&](double q) {
    const double h = q * double(sorted.size() - 1);
    const size_t lo = static_cast<size_t>(std::floor(h));
    const size_t hi = std::min(lo + 1, sorted.size() - 1);
    return sorted[lo] + (h - double(lo)) * (sorted[hi] - sorted[lo]);
  };
  s.min = sorted.front();
  s.max = sorted.back();
  s.q05 = quantile(0.05);
  s.q50 = quantile(0.5);
  s.q95 = quantile(0.95);

  // The linear fit over the parameters that vary.
  std::vector<size_t> varying;
  for (size_t j = 0; j < p; ++j) {
    const double first = values[rows.front()][j];
    for (size_t k : rows)
      if (values[k][j] != first) {
        varying.push_back(j);
        break;
      }
  }
  const long n = s.n, m = static_cast<long>(varying.size());
  if (m == 0 || n <= m + 1 || s.min == s.max) return s;  // nothing to fit
  Eigen::MatrixXd X(n, m + 1);
  Eigen::VectorXd Y(n);
  for (long i = 0; i < n; ++i) {
    const size_t k = rows[static_cast<size_t>(i)];
    X(i, 0) = 1.0;
    for (long c = 0; c < m; ++c) X(i, c + 1) = values[k][varying[static_cast<size_t>(c)]];
    Y(i) = metric[k];
  }
  // Centre the columns (conditioning); the slopes are unchanged.
  for (long c = 1; c <= m; ++c) X.col(c).array() -= X.col(c).mean();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  if (qr.rank() < m + 1) return s;
  const Eigen::VectorXd b = qr.solve(Y);
  const double rss = (Y - X * b).squaredNorm();
  const double dof = double(n - m - 1);
  const double sigma2 = rss / dof;
  const Eigen::MatrixXd cov = sigma2 * (X.transpose() * X).inverse();
  const double t = boost::math::quantile(boost::math::students_t_distribution<double>(dof), 0.975);
  for (long c = 0; c < m; ++c) {
    MetricStatistics::Sensitivity e;
    e.coefficient = b(c + 1);
    e.std_error = std::sqrt(std::max(0.0, cov(c + 1, c + 1)));
    e.low = e.coefficient - t * e.std_error;
    e.high = e.coefficient + t * e.std_error;
    s.sensitivity[varying[static_cast<size_t>(c)]] = e;
  }
  return s;
}

}  // namespace orthomech

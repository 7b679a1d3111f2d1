// `orthomech simulate FILE --t-end T`: forward dynamics (issue 5; docs/design.md §4–5, §8).
// All the mathematics is in dynamics/simulate; this file parses options and formats results.
#include "orthomech/dynamics/simulate.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/reactions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/cycle_output.hpp"
#include "orthomech/io/noise.hpp"
#include "orthomech/io/number_text.hpp"
#include "orthomech/io/units.hpp"
#include "run_bounds.hpp"

namespace orthomech::cli {

namespace {

struct SimulateCliOptions {
  std::string file;
  std::vector<std::string> sets;  // --set PATH=VALUE
  double t_end = 1.0;
  double rtol = 1e-8, atol = 1e-10, dt_out = 0.0, max_step = 0.0;
  long max_steps = kDefaultMaxSteps;
  double time_limit = 0.0;  // s of wall clock; 0: none
  std::string form = "dual";
  std::string integrator = "dopri5";
  std::vector<std::string> rates;  // NAME=VALUE
  bool json = false;
  bool positions = false;
  std::string out_dir;
  std::string units = "file";
};

// Output units of every column of simulate (measures, reactions, energies, positions).
struct SimulateUnits {
  UnitSystem system;
  OutputUnit time, energy, length;
  std::vector<OutputUnit> measures, components, positions;
  std::vector<PositionColumn> position_columns;
  SimulateUnits(const Model& model, const std::vector<ReactionComponent>& reaction_components,
                const UnitSystem& u)
      : system(u),
        time(output_unit(Dimension::time, u)),
        energy(output_unit(Dimension::moment, u)),
        length(output_unit(Dimension::length, u)),
        position_columns(orthomech::position_columns(model)) {
    for (const Measure& m : model.measures)
      measures.push_back(output_unit(dimension_of(m.unit), u));
    for (const auto& c : reaction_components)
      components.push_back(output_unit(dimension_of(c.unit), u));
    for (const PositionColumn& c : position_columns)
      positions.push_back(output_unit(c.dimension, u));
    angle = output_unit(Dimension::angle, u);
    for (const Measure& m : model.measures) measure_dims.push_back(dimension_of(m.unit));
    for (const auto& c : reaction_components) component_dims.push_back(dimension_of(c.unit));
  }
  OutputUnit angle;
  // The scale of every dimension over the samples (SampleSpool::add): rounding noise is written
  // as 0 (io/noise.hpp; a slider's y on a horizontal guide, a frictionless slide's axial force).
  NoiseFloor noise;
  std::vector<Dimension> measure_dims, component_dims;
  // SI values to output values, rounding noise as 0: measure k, reaction component k, position
  // column k, an energy.
  [[nodiscard]] double measure(size_t k, double v) const {
    return measures[k].from_si(noise.clean(measure_dims[k], v));
  }
  [[nodiscard]] double component(size_t k, double v) const {
    return components[k].from_si(noise.clean(component_dims[k], v));
  }
  [[nodiscard]] double position(size_t k, double v) const {
    return positions[k].from_si(noise.clean(position_columns[k].dimension, v));
  }
  [[nodiscard]] double energy_of(double v) const {
    return energy.from_si(noise.clean(Dimension::moment, v));
  }
};

// A file in the temporary directory ($TMPDIR, else /tmp), unlinked at once: it goes with the
// process, however that ends. `what` names it in the error.
std::FILE* temporary_file(const char* what) {
  std::string path =
      (std::filesystem::temp_directory_path() / "orthomech-simulate-XXXXXX").string();
  const int fd = ::mkstemp(path.data());
  std::FILE* f = fd >= 0 ? ::fdopen(fd, "w+b") : nullptr;
  if (fd >= 0) ::unlink(path.c_str());
  if (f == nullptr) {
    if (fd >= 0) ::close(fd);
    throw std::runtime_error(std::string("simulate: cannot create a temporary file for ") + what +
                             " in " + std::filesystem::temp_directory_path().string());
  }
  return f;
}

// The output samples, streamed out of the library (SimulateOptions::on_sample) into a temporary
// file, one row of SI values per sample, so that the memory does not grow with the number of
// outputs (issue 18 item 2: 1e6 samples held as SimulationSample cost 1.5 GB). The rounding-noise
// scale is gathered as the rows arrive; the outputs (table, CSV, JSON columns) are written from
// the file when the run is over, once that scale, which is the whole output's, is known.
// Row: t, the number of reactions of the sample, the measures, the positions (every body's pose
// and named point), the reaction components (NaN past that number), kinetic, potential, work,
// residual_length, residual_angle.
class SampleSpool {
 public:
  SampleSpool(const Model& model, SimulateUnits& units)
      : model_(model),
        U_(units),
        nm_(model.measures.size()),
        np_(units.position_columns.size()),
        nr_(units.components.size()),
        file_(temporary_file("the samples"), &std::fclose) {
    row_.resize(width());
  }
  [[nodiscard]] size_t width() const { return 2 + nm_ + np_ + nr_ + 5; }
  [[nodiscard]] size_t measure(size_t k) const { return 2 + k; }
  [[nodiscard]] size_t position(size_t k) const { return 2 + nm_ + k; }
  [[nodiscard]] size_t component(size_t k) const { return 2 + nm_ + np_ + k; }
  [[nodiscard]] size_t kinetic() const { return 2 + nm_ + np_ + nr_; }
  [[nodiscard]] size_t rows() const { return static_cast<size_t>(rows_); }

  void add(const SimulationSample& s) {
    const double nan = std::nan("");
    row_[0] = s.t;
    row_[1] = static_cast<double>(s.reactions.size());
    for (size_t k = 0; k < nm_; ++k) {
      row_[measure(k)] = k < s.measures.size() ? s.measures[k] : nan;
      U_.noise.see(dimension_of(model_.measures[k].unit), row_[measure(k)]);
    }
    compute_output_positions(model_, s.q, pose_);
    for (size_t k = 0; k < np_; ++k) {
      row_[position(k)] = pose_[k];
      U_.noise.see(U_.position_columns[k].dimension, pose_[k]);
    }
    for (size_t k = 0; k < nr_; ++k) {
      row_[component(k)] = k < s.reactions.size() ? s.reactions[k] : nan;
      U_.noise.see(U_.component_dims[k], row_[component(k)]);
    }
    const ResidualSplit r = split_residual(model_, s.q);
    const size_t e = kinetic();
    row_[e] = s.kinetic;
    row_[e + 1] = s.potential;
    row_[e + 2] = s.work;
    row_[e + 3] = r.length;
    row_[e + 4] = r.angle;
    for (const double v : {s.kinetic, s.potential, s.work}) U_.noise.see(Dimension::moment, v);
    if (std::fwrite(row_.data(), sizeof(double), row_.size(), file_.get()) != row_.size())
      throw std::runtime_error("simulate: cannot write the samples' temporary file");
    ++rows_;
  }

  // Calls f(row) for every row, in time order (read in blocks of about 1 MB).
  template <class F>
  void for_each(F&& f) const {
    std::fflush(file_.get());
    std::rewind(file_.get());
    const size_t w = width();
    const size_t block_rows = std::max<size_t>(1, kBlockBytes / (sizeof(double) * w));
    block_.resize(w * std::min(block_rows, static_cast<size_t>(rows_)));
    for (long done = 0; done < rows_;) {
      const size_t n = std::min(block_rows, static_cast<size_t>(rows_ - done));
      if (std::fread(block_.data(), sizeof(double) * w, n, file_.get()) != n)
        throw std::runtime_error("simulate: cannot read the samples' temporary file");
      for (size_t i = 0; i < n; ++i) f(block_.data() + i * w);
      done += static_cast<long>(n);
    }
  }

 private:
  static constexpr size_t kBlockBytes = size_t{1} << 20;
  const Model& model_;
  SimulateUnits& U_;
  size_t nm_, np_, nr_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_;
  std::vector<double> row_, pose_;
  mutable std::vector<double> block_;  // for_each's buffer
  long rows_ = 0;
};

std::string g(double v, int precision = 10) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

// "B0_vx=1": the rate of a measure's position quantity, in the file's units (length or angle per
// time unit).
InitialRate parse_rate(const Model& model, const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos)
    throw CLI::ValidationError("--rate",
                               "--rate '" + text + "': expected MEASURE=VALUE (the file's units)");
  const std::string name = text.substr(0, eq);
  const int m = model.find_measure(name);
  if (m < 0)
    throw CLI::ValidationError("--rate",
                               "--rate '" + text + "': measure '" + name + "' is not defined");
  const UnitSystem file = unit_system(model.units);
  const bool angle = model.measures[static_cast<size_t>(m)].unit.rfind("rad", 0) == 0;
  const double scale = (angle ? file.angle_si : file.length_si) / file.time_si;
  return {m, parse_number(text.substr(eq + 1), "--rate " + name) * scale};
}

// simulate.csv: every column with its unit in the header (the output units), every body's pose
// and named point; chart_switches.csv.
void write_csv(const std::filesystem::path& dir, const Model& model, const SimulateResult& res,
               const SampleSpool& spool, const SimulateUnits& U) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw CLI::ValidationError("--out", "cannot create " + dir.string() + ": " + ec.message());
  std::ofstream out(dir / "simulate.csv");
  out << "t [" << U.time.name << "]";
  for (size_t k = 0; k < model.measures.size(); ++k)
    out << "," << model.measures[k].name << " [" << U.measures[k].name << "]";
  for (size_t k = 0; k < U.position_columns.size(); ++k)
    out << "," << U.position_columns[k].name << " [" << U.positions[k].name << "]";
  for (size_t k = 0; k < res.components.size(); ++k)
    out << "," << res.components[k].name << " [" << U.components[k].name << "]";
  const std::string e = " [" + U.energy.name + "]";
  out << ",kinetic" << e << ",potential" << e << ",work" << e << ",energy" << e
      << ",residual_length [" << U.length.name << "],residual_angle [" << U.angle.name << "]\n";
  std::string line;  // one row's text: printf's "%.12g" per number, without printf
  const auto cell = [&](double v) {
    line += ',';
    append_number(line, v, kCsvDigits);
  };
  spool.for_each([&](const double* row) {
    line.clear();
    append_number(line, U.time.from_si(row[0]), kCsvDigits);
    for (size_t k = 0; k < model.measures.size(); ++k) cell(U.measure(k, row[spool.measure(k)]));
    for (size_t k = 0; k < U.position_columns.size(); ++k)
      cell(U.position(k, row[spool.position(k)]));
    for (size_t k = 0; k < res.components.size(); ++k)
      cell(static_cast<double>(k) < row[1] ? U.component(k, row[spool.component(k)]) : 0.0);
    const double* E = row + spool.kinetic();
    for (const double v :
         {U.energy_of(E[0]), U.energy_of(E[1]), U.energy_of(E[2]), U.energy_of(E[0] + E[1] - E[2]),
          U.length.from_si(E[3]), U.angle.from_si(E[4])})
      cell(v);
    line += '\n';
    out.write(line.data(), static_cast<std::streamsize>(line.size()));
  });
  std::ofstream sw(dir / "chart_switches.csv");
  sw << "t [" << U.time.name << "],from,to\n";
  for (const ChartSwitch& c : res.chart_switches)
    sw << number_text(U.time.from_si(c.t), kCsvDigits) << ",\"" << c.from << "\",\"" << c.to
       << "\"\n";
  out.close();
  sw.close();
  if (!out || !sw) throw CLI::ValidationError("--out", "cannot write the files in " + dir.string());
}

// The time histories as columns, one array per quantity over the output times (as plotting tools
// read them; a tenth of the objects of one record per sample, measured: 100 samples of Andrews
// cost about 2.5 ms as records). With `positions`: every body's pose and named point too. Each
// column is a function of a spool row (output units, rounding noise as 0).
using SampleColumn = std::function<double(const double*)>;

// A placeholder string no text of the document can hold (control characters around a tag).
std::string column_placeholder(size_t k) {
  return "\x01orthomech.samples." + std::to_string(k) + "\x02";
}

// The `samples` object with every array a placeholder (column_placeholder(k), k the index of
// its column in `columns`).
nlohmann::json series_columns(std::vector<SampleColumn>& columns, const Model& model,
                              const SimulateResult& res, const SampleSpool& spool,
                              const SimulateUnits& U, bool positions) {
  const auto column = [&](SampleColumn f) {
    columns.push_back(std::move(f));
    return nlohmann::json(column_placeholder(columns.size() - 1));
  };
  nlohmann::json j;
  j["t"] = column([&](const double* r) { return U.time.from_si(r[0]); });
  nlohmann::json m = nlohmann::json::object();
  for (size_t k = 0; k < model.measures.size(); ++k)
    m[model.measures[k].name] =
        column([&, k](const double* r) { return U.measure(k, r[spool.measure(k)]); });
  j["measures"] = m;
  nlohmann::json rc = nlohmann::json::object();
  for (size_t k = 0; k < res.components.size(); ++k)
    rc[res.components[k].name] = column([&, k](const double* r) {
      return static_cast<double>(k) < r[1] ? U.component(k, r[spool.component(k)]) : std::nan("");
    });
  j["reactions"] = rc;
  const size_t e = spool.kinetic();
  j["kinetic"] = column([&, e](const double* r) { return U.energy_of(r[e]); });
  j["potential"] = column([&, e](const double* r) { return U.energy_of(r[e + 1]); });
  j["work"] = column([&, e](const double* r) { return U.energy_of(r[e + 2]); });
  j["residual_length"] = column([&, e](const double* r) { return U.length.from_si(r[e + 3]); });
  j["residual_angle"] = column([&, e](const double* r) { return U.angle.from_si(r[e + 4]); });
  if (positions) {
    nlohmann::json p = nlohmann::json::object();
    for (size_t k = 0; k < U.position_columns.size(); ++k)
      p[U.position_columns[k].name] =
          column([&, k](const double* r) { return U.position(k, r[spool.position(k)]); });
    j["positions"] = p;
  }
  return j;
}

// The output columns of the spool, column by column. The values of every column are computed in
// one pass over the spool's rows and transposed in blocks of rows: held in memory when the whole
// table fits in one block, else written block by block into a second temporary file laid out
// column after column. Reading a column then reads only that column. (Reading the whole spool
// once per column cost O(columns × rows × row width): 1.4 s of the 3.25 s of N-four-bar-400 to
// --t-end 1e-9, 101 samples of 4814 columns.) Memory: one block (kBlockBytes), whatever the number
// of samples.
class ColumnTable {
 public:
  ColumnTable(const SampleSpool& spool, const std::vector<SampleColumn>& columns)
      : rows_(spool.rows()),
        cols_(columns.size()),
        block_rows_(block_rows(rows_, cols_)),
        block_(block_rows_ * cols_),
        file_(nullptr, &std::fclose) {
    if (rows_ > block_rows_) file_.reset(temporary_file("the output columns"));
    size_t r = 0, first = 0;  // rows seen; the first row of the block
    spool.for_each([&](const double* row) {
      const size_t i = r - first;
      for (size_t k = 0; k < cols_; ++k) block_[k * block_rows_ + i] = columns[k](row);
      if (++r - first == block_rows_ && file_) {
        write_block(first, block_rows_);
        first = r;
      }
    });
    if (file_ && r > first) write_block(first, r - first);
  }

  // Calls f(value) for every value of column k, in time order.
  template <class F>
  void for_each_value(size_t k, F&& f) const {
    if (!file_) {
      for (size_t i = 0; i < rows_; ++i) f(block_[k * block_rows_ + i]);
      return;
    }
    for (size_t done = 0; done < rows_;) {
      const size_t n = std::min(block_.size(), rows_ - done);
      read_values(static_cast<off_t>((k * rows_ + done) * sizeof(double)), n);
      for (size_t i = 0; i < n; ++i) f(block_[i]);
      done += n;
    }
  }

 private:
  // Rows first … first + n − 1, held in block_ (column k at k · block_rows_), to their places in
  // the file (column k's values at k · rows_).
  void write_block(size_t first, size_t n) {
    const int fd = ::fileno(file_.get());
    for (size_t k = 0; k < cols_; ++k) {
      const auto bytes = static_cast<ssize_t>(n * sizeof(double));
      const auto at = static_cast<off_t>((k * rows_ + first) * sizeof(double));
      if (::pwrite(fd, block_.data() + k * block_rows_, static_cast<size_t>(bytes), at) != bytes)
        throw std::runtime_error("simulate: cannot write the output columns' temporary file");
    }
  }
  // n values from byte `at` of the file into block_ (for_each_value's buffer).
  void read_values(off_t at, size_t n) const {
    const auto bytes = static_cast<ssize_t>(n * sizeof(double));
    if (::pread(::fileno(file_.get()), block_.data(), static_cast<size_t>(bytes), at) != bytes)
      throw std::runtime_error("simulate: cannot read the output columns' temporary file");
  }
  // Rows per block: as many as kBlockBytes hold, at most all of them.
  static size_t block_rows(size_t rows, size_t cols) {
    const size_t fit =
        std::max<size_t>(1, kBlockBytes / (sizeof(double) * std::max<size_t>(1, cols)));
    return std::max<size_t>(1, std::min(fit, rows));
  }
  static constexpr size_t kBlockBytes = size_t{4} << 20;
  size_t rows_, cols_, block_rows_;
  mutable std::vector<double> block_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_;
};

// Writes `text` (a JSON document dumped with indent 2 whose sample arrays are placeholders) to
// out with every placeholder replaced by its column (ColumnTable) and written value by
// value as nlohmann::json writes an array (one value a line, indented one level further).
void write_with_columns(std::ostream& out, const std::string& text,
                        const std::vector<SampleColumn>& columns, const SampleSpool& spool) {
  const ColumnTable table(spool, columns);
  // A placeholder as dumped: "\u0001orthomech.samples.<k>\u0002".
  const std::string mark = "\"\\u0001orthomech.samples.", end = "\\u0002\"";
  size_t at = 0;
  while (true) {
    const size_t p = text.find(mark, at);
    if (p == std::string::npos) break;
    const size_t digits = p + mark.size();
    const size_t close = text.find(end, digits);
    const size_t k = std::stoul(text.substr(digits, close - digits));
    out << text.substr(at, p - at);
    const size_t line = text.rfind('\n', p) + 1;
    const size_t indent = text.find_first_not_of(' ', line) - line;
    const std::string pad(indent + 2, ' ');
    bool first = true;
    table.for_each_value(k, [&](double v) {
      out << (first ? "[\n" : ",\n") << pad << nlohmann::json(v).dump();
      first = false;
    });
    out << (first ? "[]" : "\n" + std::string(indent, ' ') + "]");
    at = close + end.size();
  }
  out << text.substr(at);
}

nlohmann::json sample_json(const Model& model, const SimulateResult& res, const SimulationSample& s,
                           const SimulateUnits& U) {
  nlohmann::json j;
  j["t"] = U.time.from_si(s.t);
  nlohmann::json m = nlohmann::json::object();
  // (A final sample at a stop where no equation holds carries no measures: written as none.)
  for (size_t k = 0; k < model.measures.size() && k < s.measures.size(); ++k)
    m[model.measures[k].name] = U.measure(k, s.measures[k]);
  j["measures"] = m;
  nlohmann::json r = nlohmann::json::object();
  for (size_t k = 0; k < s.reactions.size() && k < res.components.size(); ++k)
    r[res.components[k].name] = U.component(k, s.reactions[k]);
  j["reactions"] = r;
  j["kinetic"] = U.energy_of(s.kinetic);
  j["potential"] = U.energy_of(s.potential);
  j["work"] = U.energy_of(s.work);
  const ResidualSplit split = split_residual(model, s.q);
  j["residual_length"] = U.length.from_si(split.length);
  j["residual_angle"] = U.angle.from_si(split.angle);
  return j;
}

// The library's options from the command line's (times in the file's unit).
SimulateOptions simulate_options(const Model& model, const SimulateCliOptions& opt) {
  const double file_time = unit_system(model.units).time_si;  // bare times: the file's unit
  SimulateOptions so;
  so.t_end = opt.t_end * file_time;
  so.rtol = opt.rtol;
  so.atol = opt.atol;
  so.dt_out = opt.dt_out * file_time;
  so.max_step = opt.max_step * file_time;
  so.max_steps = opt.max_steps;
  so.control = run_control("simulate", opt.time_limit);
  so.form = opt.form == "primal" ? DynamicsForm::primal : DynamicsForm::dual;
  if (!parse_integrator(opt.integrator, so.integrator))  // CLI::IsMember checked the name
    throw std::logic_error("simulate: integrator '" + opt.integrator + "' has no stepper");
  for (const std::string& r : opt.rates) so.initial_rates.push_back(parse_rate(model, r));
  so.record_samples = false;  // streamed into a SampleSpool (run_simulate)
  return so;
}

double relative_drift(const SimulateResult& res) {
  return res.energy_scale > 0 ? res.energy_max_drift / res.energy_scale : 0.0;
}

// The chart switches and the change points passed, as JSON arrays.
nlohmann::json chart_switches_json(const SimulateResult& res, const SimulateUnits& U) {
  nlohmann::json sw = nlohmann::json::array();
  for (const ChartSwitch& c : res.chart_switches)
    sw.push_back({{"t", U.time.from_si(c.t)}, {"from", c.from}, {"to", c.to}});
  return sw;
}
nlohmann::json passages_json(const SimulateResult& res, const SimulateUnits& U) {
  nlohmann::json cp = nlohmann::json::array();
  for (const ChangePointPassage& c : res.passages)
    cp.push_back({{"t", U.time.from_si(c.t)},
                  {"from", U.time.from_si(c.t_from)},
                  {"to", U.time.from_si(c.t_to)},
                  {"quality_from", c.sigma_from},
                  {"quality_to", c.sigma_to},
                  {"velocity_jump", c.velocity_jump},
                  {"tangent_cosine", c.tangent_cosine},
                  {"energy_balance", c.energy_balance}});
  return cp;
}

// The unit of a joint's coordinate (angle or length) in the output units.
OutputUnit joint_unit(const Model& model, int joint, const SimulateUnits& U) {
  const bool angle =
      joint_coordinate_kind(model.joints[static_cast<size_t>(joint)]) == CoordinateKind::angle;
  return output_unit(angle ? Dimension::angle : Dimension::length, U.system);
}

// The joints that left their limits (simulate does not enforce them: no end stops yet).
nlohmann::json limits_json(const Model& model, const SimulateResult& res, const SimulateUnits& U) {
  nlohmann::json a = nlohmann::json::array();
  for (const LimitExit& e : res.limits_left) {
    const Joint& joint = model.joints[static_cast<size_t>(e.joint)];
    const OutputUnit u = joint_unit(model, e.joint, U);
    a.push_back({{"joint", joint.name},
                 {"unit", u.name},
                 {"limits", {u.from_si(joint.limits->x()), u.from_si(joint.limits->y())}},
                 {"t_first", U.time.from_si(e.t_first)},
                 {"first", u.from_si(e.value_first)},
                 {"t_furthest", U.time.from_si(e.t_furthest)},
                 {"furthest", u.from_si(e.value_furthest)},
                 {"steps", e.steps}});
  }
  return a;
}

// The impacts on end stops: joint, stop, time, speeds (the coordinate's unit per time unit) and
// the energy lost.
nlohmann::json impacts_json(const Model& model, const SimulateResult& res, const SimulateUnits& U) {
  nlohmann::json a = nlohmann::json::array();
  for (const SimulateResult::StopImpact& i : res.impacts) {
    const OutputUnit u = joint_unit(model, i.joint, U);
    auto speed = [&](double v) { return u.from_si(v) * U.time.si; };
    a.push_back({{"t", U.time.from_si(i.t)},
                 {"joint", model.joints[static_cast<size_t>(i.joint)].name},
                 {"stop", i.side > 0 ? "lower" : "upper"},
                 {"speed_unit", u.name + "/" + U.time.name},
                 {"speed_before", speed(i.speed_before)},
                 {"speed_after", speed(i.speed_after)},
                 {"energy_loss", U.energy.from_si(i.energy_loss)}});
  }
  return a;
}

// The resting contacts on end stops: joint, stop, from and to (null: still resting at the end).
nlohmann::json contacts_json(const Model& model, const SimulateResult& res,
                             const SimulateUnits& U) {
  nlohmann::json a = nlohmann::json::array();
  for (const SimulateResult::StopContact& c : res.contacts)
    a.push_back(
        {{"joint", model.joints[static_cast<size_t>(c.joint)].name},
         {"stop", c.side > 0   ? "lower"
                  : c.side < 0 ? "upper"
                               : "stuck"},
         {"t_from", U.time.from_si(c.t_from)},
         {"t_to", std::isnan(c.t_to) ? nlohmann::json() : nlohmann::json(U.time.from_si(c.t_to))}});
  return a;
}

// A located warning per joint that left its limits.
void warn_limits(const Model& model, const SimulateResult& res, const SimulateUnits& U) {
  for (const LimitExit& e : res.limits_left) {
    const Joint& joint = model.joints[static_cast<size_t>(e.joint)];
    const OutputUnit u = joint_unit(model, e.joint, U);
    spdlog::warn(
        "{}: joint '{}' leaves its limits [{:.6g}, {:.6g}] {} at t = {:.6g} {} ({:.6g} {}), "
        "furthest "
        "{:.6g} {} at t = {:.6g} {}: simulate stops a joint at its limits only with end_stops: "
        "{{restitution: e}}",
        joint.where.str(), joint.name, u.from_si(joint.limits->x()), u.from_si(joint.limits->y()),
        u.name, U.time.from_si(e.t_first), U.time.name, u.from_si(e.value_first), u.name,
        u.from_si(e.value_furthest), u.name, U.time.from_si(e.t_furthest), U.time.name);
  }
}

// The --json document; its `samples` arrays are placeholders (write_with_columns).
nlohmann::json result_json(const Model& model, const UnitSystem& system, const SimulateOptions& so,
                           const SimulateResult& res, const SimulateUnits& U,
                           const nlohmann::json& samples) {
  nlohmann::json j;
  j["mechanism"] = model.name;
  j["units"] = units_json(system);
  j["status"] = to_string(res.status);
  j["message"] = res.message;
  // A run stopped at a bound holds the motion up to the stop only (docs/cli.md "Limits").
  j["complete"] = res.status != SimulateStatus::stopped;
  if (res.status == SimulateStatus::stopped) j["stop"] = to_string(res.stop);
  j["form"] = so.form == DynamicsForm::dual ? "dual" : "primal";
  j["integrator"] = to_string(so.integrator);
  j["rtol"] = so.rtol;
  j["atol"] = so.atol;
  j["final"] = sample_json(model, res, res.final, U);
  j["energy"] = {{"initial", U.energy.from_si(res.energy_initial)},
                 {"final", U.energy.from_si(res.energy_final)},
                 {"max_drift", U.energy.from_si(res.energy_max_drift)},
                 {"relative_drift", relative_drift(res)},
                 {"drift_limit", res.energy_drift_limit},
                 {"balance", res.status == SimulateStatus::energy_drift ? "drifted"
                             : res.status == SimulateStatus::completed  ? "held"
                                                                        : "unknown"}};
  j["limits_left"] = limits_json(model, res, U);
  j["load_switches"] = res.load_switches;
  j["friction_switches"] = res.friction_switches;
  j["impacts"] = impacts_json(model, res, U);
  j["contacts"] = contacts_json(model, res, U);
  j["max_residual_length"] = U.length.from_si(res.max_residual_length);
  j["max_residual_angle"] = U.angle.from_si(res.max_residual_angle);
  j["max_velocity_residual"] = res.max_velocity_residual;
  if (so.form == DynamicsForm::primal) j["max_invariant_J"] = res.max_invariant_J;
  j["kinetic_energy_removed"] = U.energy.from_si(res.kinetic_removed);
  j["steps"] = res.steps;
  j["evaluations"] = res.evaluations;
  j["rejected_steps"] = res.rejected_steps;
  j["jacobians"] = res.jacobians;
  j["chart_switches"] = chart_switches_json(res, U);
  j["change_points_passed"] = res.passages.size();
  j["change_points"] = passages_json(res, U);
  j["samples"] = samples;
  return j;
}

// The text report: a summary, then one line per output time.
void write_text(std::ostream& out, const Model& model, const SimulateCliOptions& opt,
                const SimulateOptions& so, const SimulateResult& res, const SampleSpool& spool,
                const SimulateUnits& U) {
  out << "mechanism   " << model.name << "  (" << model.file << ")\n";
  out << "form        " << opt.form << ", " << opt.integrator << ", rtol " << g(so.rtol, 3)
      << ", atol " << g(so.atol, 3) << "\n";
  out << "status      " << to_string(res.status) << (res.message.empty() ? "" : ": ") << res.message
      << "\n";
  out << "steps       " << res.steps << " (" << res.evaluations << " evaluations";
  if (res.rejected_steps > 0) out << ", " << res.rejected_steps << " rejected";
  if (res.jacobians > 0) out << ", " << res.jacobians << " Jacobians";
  out << "), " << res.passages.size() << " change points passed\n";
  if (res.load_switches > 0 || !res.impacts.empty() || res.friction_switches > 0) {
    out << "events      " << res.load_switches << " load switches (active_while), "
        << res.impacts.size() << " impacts on end stops";
    if (!res.contacts.empty()) out << ", " << res.contacts.size() << " resting contacts";
    if (res.friction_switches > 0)
      out << ", " << res.friction_switches << " reversals of pin friction";
    out << "\n";
  }
  for (const SimulateResult::StopContact& c : res.contacts)
    out << (c.side == 0 ? "stuck       joint '" : "resting     joint '")
        << model.joints[static_cast<size_t>(c.joint)].name
        << (c.side > 0   ? "' on its lower stop"
            : c.side < 0 ? "' on its upper stop"
                         : "' by its pin friction")
        << " from t = " << g(U.time.from_si(c.t_from), 9) << " " << U.time.name
        << (std::isnan(c.t_to) ? std::string(" to the end")
                               : " to " + g(U.time.from_si(c.t_to), 9) + " " + U.time.name)
        << "\n";
  const std::string eu = " " + U.energy.name;
  out << "energy      initial " << g(U.energy.from_si(res.energy_initial)) << eu << ", final "
      << g(U.energy.from_si(res.energy_final)) << eu << ", max drift "
      << g(U.energy.from_si(res.energy_max_drift), 3) << eu << " (relative "
      << g(relative_drift(res), 3) << ")\n";
  out << "residual    max |f| " << g(U.length.from_si(res.max_residual_length), 3) << " "
      << U.length.name << " (length rows), " << g(U.angle.from_si(res.max_residual_angle), 3) << " "
      << U.angle.name << " (angular rows)";
  if (so.form == DynamicsForm::primal) out << ", max |J| " << g(res.max_invariant_J, 3);
  out << "\n\n";
  out << "t [" << U.time.name << "]";
  for (size_t k = 0; k < model.measures.size(); ++k)
    out << "\t" << model.measures[k].name << " [" << U.measures[k].name << "]";
  out << "\tenergy [" << U.energy.name << "]\n";
  spool.for_each([&](const double* row) {
    out << g(U.time.from_si(row[0]), 6);
    for (size_t k = 0; k < model.measures.size(); ++k)
      out << "\t" << g(U.measure(k, row[spool.measure(k)]), 8);
    const double* E = row + spool.kinetic();
    out << "\t" << g(U.energy_of(E[0] + E[1] - E[2]), 8) << "\n";
  });
}

int run_simulate(const SimulateCliOptions& opt) {
  const Model model = load(opt.file, opt.sets);
  const UnitSystem system = resolve_units(model, opt.units);
  SimulateOptions so = simulate_options(model, opt);
  SimulateUnits U(model, reaction_components(model), system);
  SampleSpool spool(model, U);
  so.on_sample = [&spool](const SimulationSample& s) { spool.add(s); };
  // SIGINT/SIGTERM: stop, write what was computed.
  const SimulateResult res = run_bounded([&] { return simulate(model, so); });
  if (res.kinetic_removed > 0.0)
    spdlog::info("initial velocity projection removed {:.6g} {} of kinetic energy",
                 U.energy.from_si(res.kinetic_removed), U.energy.name);
  warn_limits(model, res, U);
  if (!opt.out_dir.empty()) write_csv(opt.out_dir, model, res, spool, U);
  spdlog::info(
      "{} chart switches: the dual form changed its independent velocities {} times (bookkeeping "
      "of the method; the results do not depend on it)",
      model.file, res.chart_switches.size());
  if (!res.impacts.empty())
    spdlog::info(
        "{}: {} impacts on end stops, {:.6g} {} of kinetic energy lost in them", model.file,
        res.impacts.size(),
        U.energy.from_si(std::accumulate(
            res.impacts.begin(), res.impacts.end(), 0.0,
            [](double a, const SimulateResult::StopImpact& i) { return a + i.energy_loss; })),
        U.energy.name);
  if (res.load_switches > 0)
    spdlog::info(
        "{}: the loads switched by active_while switched {} times (events, each located "
        "to {:.3g} of the run's time span)",
        model.file, res.load_switches, kEventTimeTolerance);

  const bool ok = res.status == SimulateStatus::completed;
  if (opt.json) {
    std::vector<SampleColumn> columns;
    const nlohmann::json skeleton = series_columns(columns, model, res, spool, U, opt.positions);
    write_with_columns(std::cout, result_json(model, system, so, res, U, skeleton).dump(2), columns,
                       spool);
    std::cout << '\n';
  } else {
    write_text(std::cout, model, opt, so, res, spool, U);
  }
  std::cout.flush();
  if (!ok) spdlog::error("simulate: {}: {}", to_string(res.status), res.message);
  if (res.status == SimulateStatus::stopped) return kStopped;
  return ok ? kOk : kNumerical;
}

}  // namespace

void register_simulate(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<SimulateCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "simulate", "forward dynamics: time histories of measures, reactions, energy, residuals");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  add_set_option(cmd, opt->sets);
  cmd->add_option("--t-end", opt->t_end, "end time, in the file's time unit")
      ->required()
      ->check(finite_range(0.0, kMaxGeneral, true));
  cmd->add_option("--rtol", opt->rtol, "relative tolerance")->check(finite_range(kMinRtol, 1.0));
  cmd->add_option("--atol", opt->atol, "absolute tolerance")->check(finite_range(0.0, 1e6, true));
  cmd->add_option("--dt-out", opt->dt_out,
                  "output interval (the file's time unit; default t_end/100; at most 1e6 output "
                  "samples)")
      ->check(finite_range(0.0, kMaxGeneral, true));
  cmd->add_option("--max-step", opt->max_step, "largest step (the file's time unit)")
      ->check(finite_range(0.0, kMaxGeneral, true));
  cmd->add_option("--max-steps", opt->max_steps,
                  "step budget of the whole motion (default 1e7): the run stops there with "
                  "status stopped, exit 5")
      ->check(CLI::Range(1L, kMaxMaxSteps));
  cmd->add_option("--time-limit", opt->time_limit,
                  "wall-clock limit in seconds (default: none): the run stops there with status "
                  "stopped, exit 5")
      ->check(finite_range(0.0, 1e9, true));
  cmd->add_option("--form", opt->form, "dual (default) or primal (Theorem 7)")
      ->check(CLI::IsMember({"dual", "primal"}));
  cmd->add_option("--integrator", opt->integrator,
                  "dopri5 (default), rkf78, bulirsch-stoer (long runs, tight tolerances) or "
                  "rosenbrock4 (stiff)")
      ->check(CLI::IsMember({"dopri5", "rkf78", "bulirsch-stoer", "rosenbrock4"}));
  cmd->add_option("--rate", opt->rates,
                  "initial rate MEASURE=VALUE of a measure's position quantity, in the file's "
                  "declared units (length or angle per time unit); repeatable");
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  cmd->add_flag("--positions", opt->positions,
                "with --json: every body's pose and named point at every output time");
  cmd->add_option("--out", opt->out_dir, "directory for simulate.csv and chart_switches.csv");
  add_units_option(cmd, opt->units);
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    {  // the library's own test of the request (t_end / max_step against the step budget)
      SimulateOptions o;
      o.t_end = opt->t_end;
      o.max_step = opt->max_step;
      o.max_steps = opt->max_steps;
      if (const std::string problem = request_problem(o); !problem.empty())
        throw CLI::ValidationError("--max-step", problem);
    }
    if (opt->dt_out > 0.0 && opt->t_end / opt->dt_out + 1.0 > kMaxOutputSamples)
      throw CLI::ValidationError("--dt-out",
                                 "--t-end / --dt-out gives more than 1e6 output "
                                 "samples; give a larger --dt-out");
    setup_logging(globals, *log);
    exit_code = run_simulate(*opt);
  });
}

}  // namespace orthomech::cli

#pragma once
// Shared by the subcommands: exit codes, loading with error reporting, logging set-up.
// No math here (house style: cli/ holds no math).
#include <CLI/CLI.hpp>
#include <iosfwd>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "orthomech/io/units.hpp"
#include "orthomech/model/model.hpp"

namespace CLI {
class App;
}

namespace orthomech {
class StudyDatabase;
struct Study;
struct VariantResult;
struct StudyReport;
}  // namespace orthomech

namespace orthomech::cli {

// Documented exit codes (docs/cli.md).
enum ExitCode : int {
  kOk = 0,
  kCheckFailed = 1,  // an analysis ran and a check failed
  kBadInput = 2,     // bad mechanism file or command line
  kNumerical = 3,    // numerical failure (cannot assemble, singular, no convergence)
  kInternal = 4,     // a bug: please report
  kStopped = 5,      // a run stopped at a bound (budget, time limit, SIGINT/SIGTERM): partial
};

struct GlobalOptions {
  bool quiet = false;
  bool verbose = false;
};

void setup_logging(const GlobalOptions& options);
// Logs go to `stream` (plain text) instead of stderr (colored on a terminal) from the next
// setup_logging on; nullptr: stderr again. The Python module captures them so.
void set_log_stream(std::ostream* stream);
// `-q`/`--quiet` and `-v`/`--verbose` after the command too: a subcommand's own flags, merged
// with the global ones (either place works).
struct LogFlags {
  bool quiet = false, verbose = false;
};
void add_log_flags(CLI::App* cmd, LogFlags& flags);
// setup_logging with the global options and the subcommand's flags merged.
void setup_logging(const GlobalOptions& options, const LogFlags& flags);
// A number option that must be finite and lie in [lo, hi] (or (lo, hi] with `lo_open`): NaN and
// inf are refused (CLI::Range and CLI::PositiveNumber let them through). Exit 2 naming the option.
[[nodiscard]] CLI::Validator finite_range(double lo, double hi, bool lo_open = false);
// A command-line number with no unit (e.g. "--rate x=1.5", "--velocity b=0,1"): the whole text
// is a number, finite and within the limits of Quantity::general. Throws CLI::ValidationError
// naming `option` otherwise.
[[nodiscard]] double parse_number(const std::string& text, const std::string& option);
// `--set PATH=VALUE` (repeatable) of a subcommand: changes of the mechanism file, applied in
// order before it is read (docs/cli.md "Changing the file from the command line").
void add_set_option(CLI::App* cmd, std::vector<std::string>& sets);
// Loads a mechanism with the `--set` changes; on failure throws InputError (main maps it to exit
// code 2; a problem with a change names the --set). The file's warnings (Model::warnings) go to
// the log.
[[nodiscard]] Model load(const std::string& path, const std::vector<std::string>& sets = {});
// A mechanism given as text rather than a file (the Python module's YAML text): while set, `load`
// of the file name `origin` reads `text` (messages name `origin`). An empty origin clears it.
void set_mechanism_text(const std::string& origin, const std::string& text);

// A located warning per joint with `friction:` for a command that does not apply it yet
// (`simulate`, `crosscheck`, `cycle --drivers`): its results are frictionless.
void warn_friction_not_applied(const Model& model, const std::string& command);

// Commands not yet available on spatial mechanisms (dimension: 3) refuse them with exit code 2
// (InputError naming the file and what works instead).
void require_planar(const Model& model, const std::string& command);

// `--units file|si` of a subcommand (docs/cli.md "Units"): outputs in the file's declared units
// (default) or in SI.
void add_units_option(CLI::App* cmd, std::string& choice);
// The chosen output units of a loaded model.
[[nodiscard]] UnitSystem resolve_units(const Model& model, const std::string& choice);
// Body coordinates q (centre of mass x, y and angle per body) or velocities u (vx, vy, ω; with
// `rates`) in the output units: length (per time), angle (per time). A spatial body: q = centre
// of mass x, y, z and the unit quaternion e0..e3 (unit-free, as is); u = vx, vy, vz, ωx, ωy, ωz.
[[nodiscard]] std::vector<double> coordinates_out(const Model& model, const VecX& v,
                                                  const UnitSystem& units, bool rates = false);
// The unit of the mass-metric distance √((q − q₀)ᵀ M (q − q₀)): √mass·length, e.g.
// "sqrt(kg)*mm".
[[nodiscard]] OutputUnit mass_metric_unit(const UnitSystem& units);
// A point of the frame given on the command line (`--shaking-about 35,0`): 2 numbers (planar) or
// 3 (spatial) in the file's length unit, returned in SI (z = 0 for a planar mechanism); "" is
// the origin. Throws CLI::ValidationError naming `option` otherwise.
[[nodiscard]] Vec3 parse_point(const Model& model, const std::string& text,
                               const std::string& option);
// The `units` object of every JSON document: the unit name of each kind of quantity.
[[nodiscard]] nlohmann::json units_json(const UnitSystem& units);
// A number of a study summary: null for NaN (no value) and ±inf.
[[nodiscard]] nlohmann::json number_or_null(double v);
// Creates `out` if missing and opens (or, with `resume`, reopens) its study.sqlite for the study
// (`mechanism` and `study_text` its identity) with the parameters' columns and the metric columns
// of `columns` (a variant that has them all). nullptr after logging why not (exit 2).
[[nodiscard]] std::unique_ptr<StudyDatabase> open_study_database(
    const std::string& out, bool resume, const std::string& mechanism,
    const std::string& study_text, const Study& study, const VariantResult& columns);
// The study report's options of `sweep` and `optimize` (docs/cli.md "The study report").
struct StudyReportOptions {
  std::string html, figures;         // --report FILE.html, --figures DIR
  std::vector<std::string> metrics;  // --report-metrics A,B,…
};
void add_study_report_options(CLI::App* cmd, StudyReportOptions& options);
// The report's metrics that the study does not have (columns: a variant's), each logged with the
// study's metrics; empty when all are there.
[[nodiscard]] std::vector<std::string> unknown_report_metrics(const StudyReportOptions& options,
                                                              const VariantResult& columns);
// Writes the page and the figures of `report` as the options ask (nothing when neither is given).
// Throws std::runtime_error naming a file that cannot be written.
void write_study_report(const StudyReportOptions& options, const StudyReport& report);
// The whole text of an input file (a mechanism or study file given on the command line). Throws
// InputError naming the path and `what` when it is not a regular file.
[[nodiscard]] std::string read_input_file(const std::string& path, const std::string& what);

}  // namespace orthomech::cli

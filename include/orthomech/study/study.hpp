#pragma once
// Design studies (docs/cli.md "sweep", docs/study-format.md): many variants of one mechanism file,
// each a set of `--set` changes (FileChange), each swept through its cycle; per variant the cycle's
// summary metrics in the file's units, and over the study the best variants (grid) or the
// quantiles and sensitivities of every metric (Monte Carlo).
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace orthomech {

enum class StudyKind { grid, monte_carlo };

struct StudyParameter {
  std::string path;  // FileChange path: bodies.crank.points.A.0, a parameter name, …
  std::string name;  // column name (default: the path)
  enum class Law { values, normal, uniform } law = Law::values;
  std::vector<double> values;  // grid: the values in order
  double mean = 0.0;           // normal and uniform: the nominal value (default: the file's)
  double sigma = 0.0;          // normal: standard deviation (0: always the mean)
  double tolerance = 0.0;      // uniform: mean ± tolerance
};

struct Study {
  StudyKind kind = StudyKind::grid;
  long samples = 0;        // Monte Carlo: number of variants
  std::uint64_t seed = 1;  // Monte Carlo
  int steps = 0;           // positions per cycle (0: the mechanism file's analysis steps)
  std::vector<StudyParameter> parameters;
  std::string best_metric = "drive.peak";  // grid summary: ranked by this metric
  bool best_largest = false;               // … smallest first unless `order: max`
  int best_count = 5;
};

// Reads a study file. The nominal values of `normal` and `uniform` laws without a `mean` are read
// from the mechanism file's text (`mechanism`, named `mechanism_origin`). Throws InputError naming
// file:line:column and the element.
[[nodiscard]] Study load_study(const std::string& path, const std::string& mechanism,
                               const std::string& mechanism_origin);
[[nodiscard]] Study parse_study(const std::string& text, const std::string& origin,
                                const std::string& mechanism, const std::string& mechanism_origin);

// The number of variants: the product of the grid's value counts, or the samples.
[[nodiscard]] long variant_count(const Study& study);
// The parameter values of variant `index` (0-based): the grid's mixed-radix digits (the last
// parameter fastest), or draws from the variant's own random stream (Boost.Random mt19937_64
// seeded from the study's seed and the index), so a variant's values depend on nothing else.
[[nodiscard]] std::vector<double> variant_values(const Study& study, long index);
// The FileChange text of a value: shortest decimal that reads back to the same double.
[[nodiscard]] std::string value_text(double value);

// One variant's outcome: status "completed", "stopped_at_dead_point", "failed" (the cycle could
// not be computed or stopped) or "invalid" (the changed file is not a valid mechanism); the
// cycle's message; metrics by name in the file's units (NaN where there is none).
struct VariantResult {
  long index = 0;
  std::vector<double> values;
  std::string status, message;
  std::vector<std::pair<std::string, double>> metrics;
};

// Evaluates one variant of the mechanism text (docs/cli.md "sweep": the metrics). `values` as
// variant_values. Never throws for a bad variant: it is a result with its status.
[[nodiscard]] VariantResult evaluate_variant(const std::string& mechanism,
                                             const std::string& origin, const Study& study,
                                             long index, const std::vector<double>& values);

// Evaluates the variants in `pending` on `jobs` OpenMP threads (0: all cores), calling `done`
// with each result as it finishes, one call at a time (any order). Results do not depend on the
// number of threads.
void run_variants(const std::string& mechanism, const std::string& origin, const Study& study,
                  const std::vector<long>& pending, int jobs,
                  const std::function<void(const VariantResult&)>& done);

// ---- Summary ---------------------------------------------------------------------------------
struct MetricStatistics {
  std::string metric;
  long n = 0;  // variants with a value
  double mean = 0.0, stddev = 0.0, q05 = 0.0, q50 = 0.0, q95 = 0.0, min = 0.0, max = 0.0;
  // Least-squares fit metric ≈ b0 + Σ b_j x_j over the variants with a value: per parameter its
  // coefficient (metric unit per parameter unit), standard error and 95 % confidence interval
  // (Student's t with n − p − 1 degrees of freedom). Parameters that do not vary are left out
  // (nullopt); no fit when n ≤ p + 1.
  struct Sensitivity {
    double coefficient = 0.0, std_error = 0.0, low = 0.0, high = 0.0;
  };
  std::vector<std::optional<Sensitivity>> sensitivity;
};
// Quantiles (linear interpolation between order statistics, as numpy's default) and the linear
// fit. `values[k]` are the parameter values of row k, `metric[k]` its metric (NaN: left out).
[[nodiscard]] MetricStatistics metric_statistics(const std::string& name,
                                                 const std::vector<std::vector<double>>& values,
                                                 const std::vector<double>& metric);

}  // namespace orthomech

#pragma once
// The results of a design study in SQLite (docs/cli.md "sweep"): one row per variant, committed
// as it finishes (a killed study loses nothing; `--resume` skips what is there), and the CSV
// written from it in variant order (identical whatever the number of threads or ranks).
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "orthomech/study/study.hpp"

namespace orthomech {

class StudyDatabase {
 public:
  // Opens `file`, creating the tables `study` (key, value: what the study is) and `variants`
  // (variant, one column per parameter, status, message, one column per metric). An existing
  // file is reopened only with `resume`, and only when its `study` rows equal `identity` and its
  // columns the given ones — except a `samples` entry, which may grow (a Monte Carlo study
  // extended, or a search given more evaluations: the stored count is updated). Throws
  // std::runtime_error saying why not.
  StudyDatabase(const std::filesystem::path& file, bool resume,
                const std::vector<std::pair<std::string, std::string>>& identity,
                const std::vector<std::string>& parameters,
                const std::vector<std::string>& metrics);
  ~StudyDatabase();
  StudyDatabase(const StudyDatabase&) = delete;
  StudyDatabase& operator=(const StudyDatabase&) = delete;

  // The variants already stored.
  [[nodiscard]] std::vector<long> stored() const;
  // Stores one variant in one transaction (metrics by name; a missing one is NULL).
  void insert(const VariantResult& result);

  struct Row {
    long index = 0;
    std::vector<double> values;
    std::string status, message;
    std::vector<double> metrics;  // NaN for NULL
  };
  // Every stored variant in variant order.
  [[nodiscard]] std::vector<Row> rows() const;
  [[nodiscard]] const std::vector<std::string>& parameters() const { return parameters_; }
  [[nodiscard]] const std::vector<std::string>& metrics() const { return metrics_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<std::string> parameters_, metrics_;
};

// A stored study read back, read-only (`sweep --combine`): its `study` rows (what it is: the
// mechanism and study texts, the columns, …), its parameter and metric columns and its rows in
// variant order. Throws std::runtime_error naming the file when it is not a study database.
struct StoredStudy {
  std::vector<std::pair<std::string, std::string>> identity;
  std::vector<std::string> parameters, metrics;
  std::vector<StudyDatabase::Row> rows;
};
[[nodiscard]] StoredStudy read_stored_study(const std::filesystem::path& file);

// The rows as CSV: variant, the parameters, status, the metrics, message (numbers with 17
// significant digits, empty cells for missing values; pandas.read_csv reads it as is).
[[nodiscard]] std::string study_csv(const StudyDatabase& db);

}  // namespace orthomech

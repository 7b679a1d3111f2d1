#include "orthomech/io/study_db.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace orthomech {

namespace {

std::string quoted(const std::string& name) {  // an SQL identifier
  std::string q = "\"";
  for (const char c : name) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

struct StudyDatabase::Impl {
  sqlite3* db = nullptr;
  sqlite3_stmt* insert = nullptr;
  std::string file;
  int lock = -1;  // the file's descriptor holding flock(LOCK_EX): one writer per study

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(file + ": " + what + ": " + (db ? sqlite3_errmsg(db) : "no database"));
  }
  void exec(const std::string& sql) const {
    char* error = nullptr;
    if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
      const std::string message = error ? error : "unknown error";
      sqlite3_free(error);
      throw std::runtime_error(file + ": " + message);
    }
  }
  sqlite3_stmt* prepare(const std::string& sql) const {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK) fail("SQL " + sql);
    return stmt;
  }
  ~Impl() {
    if (insert) sqlite3_finalize(insert);
    if (db) sqlite3_close(db);
    if (lock >= 0) ::close(lock);
  }
  // One study, one writer: an exclusive flock on the database file (independent of SQLite's
  // own POSIX locks, released when the process ends however it ends). A second sweep on the same
  // folder is refused instead of computing the same variants and failing on their rows.
  void lock_file() {
    lock = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
    if (lock < 0) fail("cannot open");
    if (::flock(lock, LOCK_EX | LOCK_NB) != 0)
      throw std::runtime_error(file +
                               ": another sweep is writing this study (it holds the file's "
                               "lock): wait for it to end, or give another --out");
  }
};

namespace {

std::string value_of(const std::vector<std::pair<std::string, std::string>>& rows,
                     const std::string& key) {
  for (const auto& row : rows)
    if (row.first == key) return row.second;
  return "";
}

// The stored study is the expected one but for a smaller `samples` (an extended Monte Carlo
// study): every other key equal, both sample counts numbers, the stored one at most the new one.
bool extends(const std::vector<std::pair<std::string, std::string>>& stored,
             const std::vector<std::pair<std::string, std::string>>& expected) {
  if (stored.size() != expected.size()) return false;
  for (size_t k = 0; k < stored.size(); ++k)
    if (stored[k].first != expected[k].first ||
        (stored[k].first != "samples" && stored[k].second != expected[k].second))
      return false;
  try {
    return std::stol(value_of(stored, "samples")) <= std::stol(value_of(expected, "samples"));
  } catch (const std::logic_error&) {
    return false;
  }
}

}  // namespace

StudyDatabase::StudyDatabase(const std::filesystem::path& file, bool resume,
                             const std::vector<std::pair<std::string, std::string>>& identity,
                             const std::vector<std::string>& parameters,
                             const std::vector<std::string>& metrics)
    : impl_(std::make_unique<Impl>()), parameters_(parameters), metrics_(metrics) {
  impl_->file = file.string();
  std::error_code ec;
  const bool existed = std::filesystem::exists(file, ec);
  if (existed && !resume)
    throw std::runtime_error(impl_->file +
                             ": exists: continue that study with --resume, or give another --out");
  if (sqlite3_open_v2(impl_->file.c_str(), &impl_->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                      nullptr) != SQLITE_OK)
    impl_->fail("cannot open");
  impl_->lock_file();
  sqlite3_busy_timeout(impl_->db, 10000);
  // Each insert is its own transaction, in the write-ahead log once it returns: a killed study
  // keeps every variant stored before the kill (a half-written one is rolled back). NORMAL does not
  // wait for the disk at every commit (a power cut may lose the last few; a kill loses none).
  impl_->exec("PRAGMA journal_mode = WAL");
  impl_->exec("PRAGMA synchronous = NORMAL");
  std::string columns = "variant INTEGER PRIMARY KEY";
  for (const auto& p : parameters) columns += ", " + quoted(p) + " REAL";
  columns += ", status TEXT NOT NULL, message TEXT";
  for (const auto& m : metrics) columns += ", " + quoted(m) + " REAL";
  impl_->exec("BEGIN");
  impl_->exec("CREATE TABLE IF NOT EXISTS study (key TEXT PRIMARY KEY, value TEXT NOT NULL)");
  impl_->exec("CREATE TABLE IF NOT EXISTS variants (" + columns + ")");
  // What the study is: stored on creation, compared on resume.
  sqlite3_stmt* read = impl_->prepare("SELECT key, value FROM study ORDER BY key");
  std::vector<std::pair<std::string, std::string>> stored;
  while (sqlite3_step(read) == SQLITE_ROW)
    stored.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(read, 0)),
                        reinterpret_cast<const char*>(sqlite3_column_text(read, 1)));
  sqlite3_finalize(read);
  auto expected = identity;
  expected.emplace_back("columns", columns);
  std::sort(expected.begin(), expected.end());
  if (stored.empty()) {
    sqlite3_stmt* put = impl_->prepare("INSERT INTO study (key, value) VALUES (?, ?)");
    for (const auto& [k, v] : expected) {
      sqlite3_bind_text(put, 1, k.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(put, 2, v.c_str(), -1, SQLITE_TRANSIENT);
      if (sqlite3_step(put) != SQLITE_DONE) impl_->fail("cannot store the study");
      sqlite3_reset(put);
    }
    sqlite3_finalize(put);
  } else if (stored != expected && extends(stored, expected)) {
    // A Monte Carlo study resumed with more samples: the stored variants are its first ones.
    sqlite3_stmt* put = impl_->prepare("UPDATE study SET value = ? WHERE key = 'samples'");
    const std::string samples = value_of(expected, "samples");
    sqlite3_bind_text(put, 1, samples.c_str(), -1, SQLITE_TRANSIENT);
    if (sqlite3_step(put) != SQLITE_DONE) impl_->fail("cannot store the study");
    sqlite3_finalize(put);
  } else if (stored != expected) {
    std::string differ;
    for (const auto& entry : expected) {  // (not a structured binding: clang 14 cannot capture one)
      const auto it = std::find_if(stored.begin(), stored.end(),
                                   [&](const auto& s) { return s.first == entry.first; });
      if (it == stored.end() || it->second != entry.second)
        differ += (differ.empty() ? "" : ", ") + entry.first;
    }
    impl_->exec("ROLLBACK");
    throw std::runtime_error(
        impl_->file + ": holds another study (" +
        (differ.empty() ? std::string("other keys") : differ) +
        " differ): --resume continues only the same study; give another --out");
  }
  impl_->exec("COMMIT");
  std::string sql = "INSERT INTO variants VALUES (?";
  for (size_t i = 0; i < parameters.size() + 2 + metrics.size(); ++i) sql += ", ?";
  impl_->insert = impl_->prepare(sql + ")");
}

StudyDatabase::~StudyDatabase() = default;

std::vector<long> StudyDatabase::stored() const {
  sqlite3_stmt* q = impl_->prepare("SELECT variant FROM variants ORDER BY variant");
  std::vector<long> out;
  while (sqlite3_step(q) == SQLITE_ROW)
    out.push_back(static_cast<long>(sqlite3_column_int64(q, 0)));
  sqlite3_finalize(q);
  return out;
}

void StudyDatabase::insert(const VariantResult& r) {
  sqlite3_stmt* s = impl_->insert;
  int k = 1;
  sqlite3_bind_int64(s, k++, r.index);
  for (size_t j = 0; j < parameters_.size(); ++j) sqlite3_bind_double(s, k++, r.values.at(j));
  sqlite3_bind_text(s, k++, r.status.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s, k++, r.message.c_str(), -1, SQLITE_TRANSIENT);
  for (const std::string& m : metrics_) {
    double v = std::numeric_limits<double>::quiet_NaN();
    for (const auto& [name, value] : r.metrics)
      if (name == m) v = value;
    if (std::isnan(v))
      sqlite3_bind_null(s, k++);
    else
      sqlite3_bind_double(s, k++, v);
  }
  const int rc = sqlite3_step(s);
  sqlite3_reset(s);
  sqlite3_clear_bindings(s);
  if (rc != SQLITE_DONE) impl_->fail("cannot store variant " + std::to_string(r.index));
}

namespace {

// Every row of the variants table in variant order (`parameters` and `metrics` columns around
// status and message).
std::vector<StudyDatabase::Row> read_rows(sqlite3_stmt* q, size_t parameters, size_t metrics) {
  std::vector<StudyDatabase::Row> out;
  const auto number = [&](int column) {
    return sqlite3_column_type(q, column) == SQLITE_NULL ? std::numeric_limits<double>::quiet_NaN()
                                                         : sqlite3_column_double(q, column);
  };
  while (sqlite3_step(q) == SQLITE_ROW) {
    StudyDatabase::Row row;
    int c = 0;
    row.index = static_cast<long>(sqlite3_column_int64(q, c++));
    for (size_t j = 0; j < parameters; ++j) row.values.push_back(number(c++));
    const auto text = [&](int column) {
      const unsigned char* t = sqlite3_column_text(q, column);
      return t ? std::string(reinterpret_cast<const char*>(t)) : std::string();
    };
    row.status = text(c++);
    row.message = text(c++);
    for (size_t m = 0; m < metrics; ++m) row.metrics.push_back(number(c++));
    out.push_back(std::move(row));
  }
  sqlite3_finalize(q);
  return out;
}

}  // namespace

std::vector<StudyDatabase::Row> StudyDatabase::rows() const {
  return read_rows(impl_->prepare("SELECT * FROM variants ORDER BY variant"), parameters_.size(),
                   metrics_.size());
}

StoredStudy read_stored_study(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw std::runtime_error(file.string() + ": no study here (no such file)");
  sqlite3* db = nullptr;
  const auto fail = [&](const std::string& what) {
    const std::string message =
        file.string() + ": " + what + (db ? std::string(": ") + sqlite3_errmsg(db) : std::string());
    if (db) sqlite3_close(db);
    return std::runtime_error(message);
  };
  if (sqlite3_open_v2(file.string().c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
    throw fail("cannot open");
  sqlite3_busy_timeout(db, 10000);
  const auto prepare = [&](const char* sql) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr) != SQLITE_OK)
      throw fail("not a study database");
    return stmt;
  };
  StoredStudy s;
  sqlite3_stmt* keys = prepare("SELECT key, value FROM study ORDER BY key");
  while (sqlite3_step(keys) == SQLITE_ROW)
    s.identity.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(keys, 0)),
                            reinterpret_cast<const char*>(sqlite3_column_text(keys, 1)));
  sqlite3_finalize(keys);
  // The columns: variant, the parameters, status, message, the metrics.
  sqlite3_stmt* info = prepare("PRAGMA table_info(variants)");
  std::vector<std::string> columns;
  while (sqlite3_step(info) == SQLITE_ROW)
    columns.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(info, 1)));
  sqlite3_finalize(info);
  const auto status = std::find(columns.begin(), columns.end(), "status");
  if (columns.size() < 3 || columns.front() != "variant" || status == columns.end() ||
      status + 1 == columns.end() || *(status + 1) != "message")
    throw fail("not a study database (its variants table has other columns)");
  s.parameters.assign(columns.begin() + 1, status);
  s.metrics.assign(status + 2, columns.end());
  s.rows = read_rows(prepare("SELECT * FROM variants ORDER BY variant"), s.parameters.size(),
                     s.metrics.size());
  sqlite3_close(db);
  return s;
}

std::string study_csv(const StudyDatabase& db) {
  const auto cell = [](const std::string& text) {
    if (text.find_first_of(",\"\n") == std::string::npos) return text;
    std::string q = "\"";
    for (const char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  const auto number = [](double v) { return std::isnan(v) ? std::string() : value_text(v); };
  std::string out = "variant";
  const auto add = [&out](const std::string& text) {  // one cell after a comma
    out += ',';
    out += text;
  };
  for (const auto& p : db.parameters()) add(cell(p));
  add("status");
  for (const auto& m : db.metrics()) add(cell(m));
  add("message");
  out += '\n';
  for (const StudyDatabase::Row& r : db.rows()) {
    out += std::to_string(r.index);
    for (double v : r.values) add(number(v));
    add(cell(r.status));
    for (double v : r.metrics) add(number(v));
    add(cell(r.message));
    out += '\n';
  }
  return out;
}

}  // namespace orthomech

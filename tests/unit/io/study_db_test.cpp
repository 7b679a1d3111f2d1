// The study database (src/io/study_db.cpp, SQLite): variants stored in any order come back in
// variant order with their values, missing metrics as NaN (empty CSV cells); reopening needs
// `resume` and the same identity and columns; the CSV quotes what CSV must quote (RFC 4180) and
// writes numbers that read back to the same double.
#include "orthomech/io/study_db.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

const std::vector<std::pair<std::string, std::string>> kIdentity = {{"mechanism", "abc"},
                                                                    {"steps", "36"}};
const std::vector<std::string> kParameters = {"L", "r"};
const std::vector<std::string> kMetrics = {"power.mean", "stroke"};

VariantResult variant(long index, double L, double r, const std::string& status) {
  VariantResult v;
  v.index = index;
  v.values = {L, r};
  v.status = status;
  return v;
}

TEST(StudyDb, VariantsComeBackInOrderAndResumeChecksTheIdentity) {
  const test::TempDir dir("orthomech_study_db_", true);
  const auto file = dir.path / "study.sqlite";
  {
    StudyDatabase db(file, false, kIdentity, kParameters, kMetrics);
    VariantResult b = variant(2, 0.1, 1.0 / 3.0, "ok");
    b.metrics = {{"power.mean", -12.5}, {"stroke", 0.1 + 0.2}};
    db.insert(b);
    VariantResult a = variant(0, 0.08, 0.03, "failed");
    a.message = "cannot close, \"joint B\"";
    db.insert(a);  // no metrics: NULL
    EXPECT_EQ(db.stored(), (std::vector<long>{0, 2}));
  }
  // An existing file needs resume.
  EXPECT_THROW(StudyDatabase(file, false, kIdentity, kParameters, kMetrics), std::runtime_error);
  // A different study or different columns are refused.
  EXPECT_THROW(
      StudyDatabase(file, true, {{"mechanism", "xyz"}, {"steps", "36"}}, kParameters, kMetrics),
      std::runtime_error);
  EXPECT_THROW(StudyDatabase(file, true, kIdentity, kParameters, {"power.mean"}),
               std::runtime_error);
  StudyDatabase db(file, true, kIdentity, kParameters, kMetrics);
  const auto rows = db.rows();
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].index, 0);
  EXPECT_EQ(rows[0].status, "failed");
  EXPECT_EQ(rows[0].message, "cannot close, \"joint B\"");
  EXPECT_TRUE(std::isnan(rows[0].metrics[0]));
  EXPECT_EQ(rows[1].index, 2);
  EXPECT_EQ(rows[1].values, (std::vector<double>{0.1, 1.0 / 3.0}));
  EXPECT_EQ(rows[1].metrics, (std::vector<double>{-12.5, 0.1 + 0.2}));

  const std::string csv = study_csv(db);
  std::istringstream in(csv);
  std::string header, first, second;
  std::getline(in, header);
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_EQ(header, "variant,L,r,status,power.mean,stroke,message");
  // Missing metrics are empty cells; a message with a comma and quotes is quoted (RFC 4180).
  EXPECT_TRUE(first.ends_with(",failed,,,\"cannot close, \"\"joint B\"\"\"")) << first;
  std::istringstream first_cells(first);
  std::string v0, L0, r0;
  std::getline(first_cells, v0, ',');
  std::getline(first_cells, L0, ',');
  std::getline(first_cells, r0, ',');
  EXPECT_EQ(v0, "0");
  EXPECT_EQ(std::stod(L0), 0.08);
  EXPECT_EQ(std::stod(r0), 0.03);
  // Numbers read back to the same double.
  std::istringstream cells(second);
  std::string cell;
  std::vector<std::string> parts;
  while (std::getline(cells, cell, ',')) parts.push_back(cell);
  ASSERT_GE(parts.size(), 6u);
  EXPECT_EQ(parts[0], "2");
  EXPECT_EQ(std::stod(parts[2]), 1.0 / 3.0);
  EXPECT_EQ(parts[3], "ok");
  EXPECT_EQ(std::stod(parts[4]), -12.5);
  EXPECT_EQ(std::stod(parts[5]), 0.1 + 0.2);
}

TEST(StudyDb, ASecondWriterOfTheSameStudyIsRefusedWhileTheFirstHoldsIt) {
  // Issue 47: two `sweep --resume` on one folder computed the same variants and the second
  // failed on their rows (exit 4). The second is now refused at once, the first goes on, and
  // once the first is closed the study opens again.
  const test::TempDir dir("orthomech_study_db_", true);
  const auto file = dir.path / "study.sqlite";
  StudyDatabase first(file, false, kIdentity, kParameters, kMetrics);
  first.insert(variant(0, 0.08, 0.03, "completed"));
  try {
    StudyDatabase second(file, true, kIdentity, kParameters, kMetrics);
    ADD_FAILURE() << "a second writer was let in";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another sweep is writing this study"), std::string::npos)
        << e.what();
  }
  first.insert(variant(1, 0.08, 0.04, "completed"));
  EXPECT_EQ(first.stored(), (std::vector<long>{0, 1}));
}

TEST(StudyDb, TheLockIsReleasedWhenTheWriterCloses) {
  const test::TempDir dir("orthomech_study_db_", true);
  const auto file = dir.path / "study.sqlite";
  { StudyDatabase first(file, false, kIdentity, kParameters, kMetrics); }
  StudyDatabase again(file, true, kIdentity, kParameters, kMetrics);
  EXPECT_TRUE(again.stored().empty());
}

}  // namespace
}  // namespace orthomech

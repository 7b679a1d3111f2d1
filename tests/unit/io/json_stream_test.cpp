// write_json_streaming_array (include/orthomech/io/json_stream.hpp) against its oracle,
// nlohmann::json's own dump(2) of the whole document with the array in place: byte for byte, for
// items that are objects (nested objects and arrays, strings with escapes, null, booleans,
// doubles), scalars and empty containers, for an empty array, and for keys sorted before and after
// the streamed one.
#include "orthomech/io/json_stream.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>

namespace orthomech {
namespace {

std::string streamed(nlohmann::json skeleton, const std::string& key, const nlohmann::json& items) {
  skeleton[key] = kJsonStreamPlaceholder;
  std::ostringstream out;
  write_json_streaming_array(out, skeleton.dump(2), items.size(),
                             [&](std::size_t i) { return items[i].dump(2); });
  return out.str();
}

std::string whole(nlohmann::json skeleton, const std::string& key, const nlohmann::json& items) {
  skeleton[key] = items;
  return skeleton.dump(2);
}

nlohmann::json skeleton() {
  nlohmann::json j;
  j["alpha"] = {{"nested", {1, 2.5, -3e-300}}, {"text", "a \"quoted\"\n\ttext"}};
  j["status"] = "completed";
  j["zeta"] = nlohmann::json::array();
  return j;
}

TEST(JsonStream, ObjectItemsAreWrittenAsTheWholeDocumentsDump) {
  nlohmann::json items = nlohmann::json::array();
  for (int i = 0; i < 5; ++i)
    items.push_back({{"input", 0.1 * i},
                     {"poses", {{"crank", {1.0 / 3.0, 2.0, -0.0}}, {"rocker", {1e300, 4}}}},
                     {"reactions", nlohmann::json::object()},
                     {"outside_limits", nlohmann::json::array()},
                     {"drive", i % 2 ? nlohmann::json(nullptr) : nlohmann::json(1e-17 * i)},
                     {"singular", i == 3},
                     {"name", "p\u00e9 \x01"}});
  for (const char* key : {"points", "a", "zz", "status_"})  // before, after, between the keys
    EXPECT_EQ(streamed(skeleton(), key, items), whole(skeleton(), key, items)) << key;
}

TEST(JsonStream, ScalarAndEmptyItemsAndAnEmptyArray) {
  const nlohmann::json scalars = {1,
                                  -2.25,
                                  "x",
                                  nullptr,
                                  true,
                                  nlohmann::json::array(),
                                  nlohmann::json::object(),
                                  nlohmann::json::array({1, {2, 3}})};
  EXPECT_EQ(streamed(skeleton(), "points", scalars), whole(skeleton(), "points", scalars));
  EXPECT_EQ(streamed(skeleton(), "points", nlohmann::json::array()),
            whole(skeleton(), "points", nlohmann::json::array()));
  // A document holding nothing but the array.
  EXPECT_EQ(streamed(nlohmann::json::object(), "points", scalars),
            whole(nlohmann::json::object(), "points", scalars));
}

TEST(JsonStream, TheKeyOfTheSkeletonIsReplaced) {
  nlohmann::json j = skeleton();
  j["points"] = "held before";
  const nlohmann::json items = {1, 2};
  EXPECT_EQ(streamed(j, "points", items), whole(skeleton(), "points", items));
}

TEST(JsonStream, ADocumentWithoutThePlaceholderIsRefused) {
  std::ostringstream out;
  EXPECT_THROW(write_json_streaming_array(out, skeleton().dump(2), 1,
                                          [](std::size_t) { return std::string("1"); }),
               std::logic_error);
}

}  // namespace
}  // namespace orthomech

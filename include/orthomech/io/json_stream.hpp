#pragma once
// A JSON document with one large array written item by item (docs/cli.md "Limits and budgets"):
// `cycle --json --positions` and `cycle --drivers --json` at 1e5 positions built a tree of about
// 1 GB for a 130–330 MB text. The text written is byte for byte the one of document.dump(2) with
// the array in place; only one item is held at a time.
#include <cstddef>
#include <functional>
#include <iosfwd>
#include <nlohmann/json_fwd.hpp>
#include <string>

namespace orthomech {

// Writes `document` as document.dump(2) would, with the top-level key `key` an array of `count`
// items, item(i) for i = 0 … count − 1, made and written one at a time. `document` must not hold
// `key` (it is replaced).
void write_json_streaming_array(std::ostream& out, nlohmann::json document, const std::string& key,
                                std::size_t count,
                                const std::function<nlohmann::json(std::size_t)>& item);

}  // namespace orthomech

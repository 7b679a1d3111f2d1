#pragma once
// A JSON document with one large array written item by item (docs/cli.md "Limits and budgets"):
// `cycle --json --positions` and `cycle --drivers --json` at 1e5 positions built a tree of about
// 1 GB for a 130–330 MB text. The text written is byte for byte the one the whole document
// dumped with indent 2 would have; only one item is held at a time.
#include <cstddef>
#include <functional>
#include <iosfwd>
#include <string>

namespace orthomech {

// The value to put at the streamed key before the document is dumped (a string no document of
// the tool holds: control characters are escaped as \u00XX in the dump).
inline constexpr const char* kJsonStreamPlaceholder = "\x01orthomech.stream\x02";

// Writes `text` — a JSON document dumped with indent 2 (nlohmann::json::dump(2)) whose value at
// one top-level key is kJsonStreamPlaceholder — with that value replaced by the array of `count`
// items, item(i) being item i dumped with indent 2, each made and written one at a time.
void write_json_streaming_array(std::ostream& out, const std::string& text, std::size_t count,
                                const std::function<std::string(std::size_t)>& item);

}  // namespace orthomech

#include "orthomech/io/json_stream.hpp"

#include <nlohmann/json.hpp>
#include <ostream>
#include <stdexcept>
#include <string_view>

namespace orthomech {

void write_json_streaming_array(std::ostream& out, nlohmann::json document, const std::string& key,
                                std::size_t count,
                                const std::function<nlohmann::json(std::size_t)>& item) {
  // A placeholder no document of the tool holds (control characters are escaped as \u00XX).
  const std::string placeholder = "\x01orthomech.stream\x02";
  document[key] = placeholder;
  const std::string text = document.dump(2);
  const std::string mark = nlohmann::json(placeholder).dump();
  const std::size_t at = text.find(mark);
  if (at == std::string::npos)
    throw std::logic_error("write_json_streaming_array: the placeholder was not written");
  // The array's indentation: that of the line holding "key": (dump(2) indents items 2 further).
  const std::size_t line = text.rfind('\n', at) + 1;
  const std::size_t indent = text.find_first_not_of(' ', line) - line;
  const std::string pad(indent + 2, ' ');
  out << std::string_view(text).substr(0, at);
  if (count == 0) {
    out << "[]";
  } else {
    out << "[\n";
    std::string piece;
    for (std::size_t i = 0; i < count; ++i) {
      piece = item(i).dump(2);
      // Every line of the item indented by `pad`.
      out << pad;
      std::size_t from = 0;
      for (std::size_t nl = piece.find('\n'); nl != std::string::npos;
           from = nl + 1, nl = piece.find('\n', from))
        out << std::string_view(piece).substr(from, nl + 1 - from) << pad;
      out << std::string_view(piece).substr(from) << (i + 1 < count ? ",\n" : "\n");
    }
    out << std::string(indent, ' ') << "]";
  }
  out << std::string_view(text).substr(at + mark.size());
}

}  // namespace orthomech

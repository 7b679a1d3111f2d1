#include "orthomech/io/json_stream.hpp"

#include <ostream>
#include <stdexcept>
#include <string_view>

namespace orthomech {

void write_json_streaming_array(std::ostream& out, const std::string& text, std::size_t count,
                                const std::function<std::string(std::size_t)>& item) {
  // The placeholder as dumped: its control characters escaped.
  const std::string mark = "\"\\u0001orthomech.stream\\u0002\"";
  const std::size_t at = text.find(mark);
  if (at == std::string::npos)
    throw std::logic_error("write_json_streaming_array: the document holds no placeholder");
  // The array's indentation: that of the line holding the key (dump(2) indents items 2 further).
  const std::size_t line = text.rfind('\n', at) + 1;
  const std::size_t indent = text.find_first_not_of(' ', line) - line;
  const std::string pad(indent + 2, ' ');
  const std::string_view whole(text);
  out << whole.substr(0, at);
  if (count == 0) {
    out << "[]";
  } else {
    out << "[\n";
    for (std::size_t i = 0; i < count; ++i) {
      const std::string piece = item(i);
      const std::string_view p(piece);
      out << pad;  // every line of the item indented by `pad`
      std::size_t from = 0;
      for (std::size_t nl = p.find('\n'); nl != std::string_view::npos;
           from = nl + 1, nl = p.find('\n', from))
        out << p.substr(from, nl + 1 - from) << pad;
      out << p.substr(from) << (i + 1 < count ? ",\n" : "\n");
    }
    out << std::string(indent, ' ') << "]";
  }
  out << whole.substr(at + mark.size());
}

}  // namespace orthomech

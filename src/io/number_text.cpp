#include "orthomech/io/number_text.hpp"

#include <charconv>
#include <stdexcept>
#include <system_error>

namespace orthomech {

void append_number(std::string& out, double v, int precision) {
  if (precision < 1 || precision > 17)
    throw std::invalid_argument("append_number: the precision must be 1 … 17");
  char buf[kNumberTextMax];
  const std::to_chars_result r =
      std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, precision);
  if (r.ec != std::errc()) throw std::logic_error("append_number: the text does not fit");
  out.append(buf, r.ptr);
}

std::string number_text(double v, int precision) {
  std::string s;
  append_number(s, v, precision);
  return s;
}

}  // namespace orthomech

#include "orthomech/error.hpp"

#include <sstream>

namespace orthomech {

std::string SourceLocation::str() const {
  std::ostringstream s;
  s << (file.empty() ? "<input>" : file);
  if (line > 0) {
    s << ':' << line;
    if (column > 0) s << ':' << column;
  }
  return s.str();
}

namespace {
std::string compose(const SourceLocation& where, const std::string& element,
                    const std::string& message) {
  std::ostringstream s;
  s << where.str() << ": error: ";
  if (!element.empty()) s << element << ": ";
  s << message;
  return s.str();
}
}  // namespace

InputError::InputError(SourceLocation where, std::string element, std::string message)
    : std::runtime_error(compose(where, element, message)),
      where_(std::move(where)),
      element_(std::move(element)),
      message_(std::move(message)) {}

}  // namespace orthomech

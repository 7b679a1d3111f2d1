#pragma once
// Errors of the "bad input" channel (house style, Errors table): one type, thrown only while a
// mechanism file is read or a Model is built; it names the file, line, column and element.
#include <stdexcept>
#include <string>

namespace orthomech {

// Where a thing was written in a mechanism file (1-based line and column; 0 = unknown).
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;
  [[nodiscard]] std::string str() const;  // "file:line:column" (or less, if unknown)
};

class InputError : public std::runtime_error {
 public:
  InputError(SourceLocation where, std::string element, std::string message);
  [[nodiscard]] const SourceLocation& where() const { return where_; }
  [[nodiscard]] const std::string& element() const { return element_; }
  [[nodiscard]] const std::string& message() const { return message_; }

 private:
  SourceLocation where_;
  std::string element_;
  std::string message_;
};

}  // namespace orthomech

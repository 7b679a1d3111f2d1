#pragma once
// Arithmetic on the named design variables of a mechanism file (docs/file-format.md
// "Parameters"): `L/2`, `2*r + 5`, `sqrt(a^2 + b^2)`, `atan2(b, a) * 180 / pi`. Evaluated by
// muparser (Debian libmuparser-dev), hidden behind this small interface so that no muparser type
// leaves src/io.
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace orthomech::detail {

// An expression names something that is not a declared parameter.
struct UnknownName : std::invalid_argument {
  UnknownName(const std::string& message, std::string name_)
      : std::invalid_argument(message), name(std::move(name_)) {}
  std::string name;
};

class Expressions {
 public:
  Expressions();
  ~Expressions();
  Expressions(const Expressions&) = delete;
  Expressions& operator=(const Expressions&) = delete;

  // Declares a parameter. Throws std::invalid_argument when the name is not an identifier
  // (a letter or '_' first, then letters, digits, '_'), is declared twice, or is the name of a
  // built-in function or of the constant `pi`.
  void define(const std::string& name, double value);
  // The value of an expression of the declared parameters (one value). Throws
  // std::invalid_argument saying what is wrong (UnknownName for an unknown identifier).
  [[nodiscard]] double evaluate(const std::string& text) const;
  // The declared parameters in declaration order.
  [[nodiscard]] const std::vector<std::pair<std::string, double>>& parameters() const {
    return parameters_;
  }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<std::pair<std::string, double>> parameters_;
};

}  // namespace orthomech::detail

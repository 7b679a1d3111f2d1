#include "expressions.hpp"

#include <muParser.h>

#include <cctype>
#include <numbers>
#include <stdexcept>

namespace orthomech::detail {

struct Expressions::Impl {
  mu::Parser parser;
};

Expressions::Expressions() : impl_(std::make_unique<Impl>()) {
  impl_->parser.DefineConst("pi", std::numbers::pi);
}

Expressions::~Expressions() = default;

namespace {

bool is_identifier(const std::string& name) {
  if (name.empty() || !(std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_'))
    return false;
  for (const char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

}  // namespace

void Expressions::define(const std::string& name, double value) {
  if (!is_identifier(name))
    throw std::invalid_argument("'" + name +
                                "' is not a parameter name (a letter or '_' first, then letters, "
                                "digits or '_')");
  if (name == "pi") throw std::invalid_argument("'pi' is predefined (3.14159...)");
  for (const auto& [known, v] : parameters_)
    if (known == name) throw std::invalid_argument("parameter '" + name + "' is declared twice");
  const auto& functions = impl_->parser.GetFunDef();
  if (functions.find(name) != functions.end())
    throw std::invalid_argument("'" + name + "' is the name of a built-in function");
  try {
    impl_->parser.DefineConst(name, value);
  } catch (const mu::Parser::exception_type& e) {
    throw std::invalid_argument("'" + name + "' cannot be a parameter name: " + e.GetMsg());
  }
  parameters_.emplace_back(name, value);
}

double Expressions::evaluate(const std::string& text) const {
  try {
    impl_->parser.SetExpr(text);
    const double value = impl_->parser.Eval();
    if (impl_->parser.GetNumResults() != 1)
      throw std::invalid_argument("'" + text + "' must be one value, not a list separated by ','");
    return value;
  } catch (const mu::Parser::exception_type& e) {
    if (e.GetCode() == mu::ecUNASSIGNABLE_TOKEN && is_identifier(e.GetToken())) {
      if (parameters_.empty())
        throw UnknownName("'" + e.GetToken() + "' is not a number and no parameter is declared",
                          e.GetToken());
      std::string names;
      for (const auto& [name, v] : parameters_) names += (names.empty() ? "" : ", ") + name;
      throw UnknownName("'" + e.GetToken() + "' is not a parameter (parameters: " + names + ")",
                        e.GetToken());
    }
    throw std::invalid_argument("cannot evaluate '" + text + "': " + e.GetMsg());
  }
}

}  // namespace orthomech::detail

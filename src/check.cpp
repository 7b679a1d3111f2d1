#include "orthomech/check.hpp"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace orthomech {

void check_failed(const char* file, int line, const char* condition,
                  std::string_view what) noexcept {
  // stdio, not iostreams: usable before static initialisation is complete and after a throw.
  std::fprintf(stderr, "%s:%d: check failed: %s (%.*s)\n", file, line, condition,
               static_cast<int>(what.size()), what.data());
  std::fflush(stderr);
  std::abort();
}

void throw_invalid_argument(std::string_view function, std::string_view argument,
                            std::string_view what) {
  std::string message;
  message.reserve(function.size() + argument.size() + what.size() + 16);
  message.append(function).append(": argument '").append(argument).append("' ").append(what);
  throw std::invalid_argument(message);
}

}  // namespace orthomech

#pragma once
// The one assertion facility (house style, "Errors"): three kinds of check, one per channel.
//
//   ORTHOMECH_DEBUG_CHECK(cond, what)  a bug in our code, checked in debug builds only (compiled
//                                      out under NDEBUG): prints "file:line: check failed: cond
//                                      (what)" to stderr and aborts.
//   ORTHOMECH_CHECK(cond, what)        the same, always on (Release too): for invariants whose
//                                      violation would silently give wrong numbers.
//   check_argument(ok, function, argument, what)
//                                      API misuse at a public entry point (wrong sizes, an index
//                                      out of range): throws std::invalid_argument
//                                      "function: argument 'argument' what", naming the argument.
//                                      Allocation-free while ok (string_views, the message is built
//                                      only on failure); not for inner loops.
//
// Bad mechanism files are InputError (orthomech/error.hpp); numerical failures are results.
#include <string_view>

namespace orthomech {

// Prints "file:line: check failed: condition (what)" to stderr and aborts (never returns).
[[noreturn]] void check_failed(const char* file, int line, const char* condition,
                               std::string_view what) noexcept;

// Throws std::invalid_argument("function: argument 'argument' what").
[[noreturn]] void throw_invalid_argument(std::string_view function, std::string_view argument,
                                         std::string_view what);

// Argument check at a public entry point: throws std::invalid_argument naming `argument` of
// `function` unless `ok`.
inline void check_argument(bool ok, std::string_view function, std::string_view argument,
                           std::string_view what) {
  if (!ok) throw_invalid_argument(function, argument, what);
}

}  // namespace orthomech

// Always-on check: aborts with file:line when `cond` is false.
#define ORTHOMECH_CHECK(cond, what)                                          \
  do {                                                                       \
    if (!(cond)) ::orthomech::check_failed(__FILE__, __LINE__, #cond, what); \
  } while (false)

// Debug-only check: as ORTHOMECH_CHECK without NDEBUG; nothing (cond not evaluated) with it.
#ifdef NDEBUG
#define ORTHOMECH_DEBUG_CHECK(cond, what) \
  do {                                    \
  } while (false)
#else
#define ORTHOMECH_DEBUG_CHECK(cond, what) ORTHOMECH_CHECK(cond, what)
#endif

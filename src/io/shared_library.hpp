#pragma once
// A shared library opened when a command first needs it (dlopen), for the libraries only some
// commands use: Cairo (`render`, the pictures of `cycle`) and Open MPI (`sweep` under mpirun).
// Linked at build time, each was mapped with its dependencies, and its symbols looked up, at the
// start of every command: 26 of the 51 shared libraries the CLI loaded were theirs
// (docs/performance.md, "Andrews' squeezer: the start"). Private to the library.
#include <initializer_list>
#include <string>

namespace orthomech::detail {

class SharedLibrary {
 public:
  // Opens the first of `names` (sonames) that loads, resolving every symbol now (RTLD_NOW); with
  // `global` its symbols also resolve the libraries it opens later itself (RTLD_GLOBAL: Open MPI's
  // components). Throws std::runtime_error naming the sonames, the loader's message and the
  // Debian package that provides them.
  SharedLibrary(std::initializer_list<const char*> names, bool global, const char* package);
  // Kept open for the life of the process (Cairo's caches and MPI's state live until exit).
  SharedLibrary(const SharedLibrary&) = delete;
  SharedLibrary& operator=(const SharedLibrary&) = delete;
  ~SharedLibrary() = default;

  // The address of `symbol` (a function or an object); throws std::runtime_error naming it and
  // the library when it is missing.
  [[nodiscard]] void* symbol(const char* name) const;
  // A function of the library, typed as its declaration (an unevaluated decltype, so that the
  // program holds no link-time reference to it):
  // function<decltype(::cairo_create)>("cairo_create").
  template <class F>
  [[nodiscard]] F* function(const char* name) const {
    return reinterpret_cast<F*>(
        symbol(name));  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast)
  }
  [[nodiscard]] const std::string& name() const { return name_; }

 private:
  void* handle_ = nullptr;
  std::string name_;
};

}  // namespace orthomech::detail

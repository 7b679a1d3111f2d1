#include "shared_library.hpp"

#include <dlfcn.h>

#include <stdexcept>

namespace orthomech::detail {

SharedLibrary::SharedLibrary(std::initializer_list<const char*> names, bool global,
                             const char* package) {
  std::string tried, why;
  for (const char* n : names) {
    handle_ = dlopen(n, RTLD_NOW | (global ? RTLD_GLOBAL : RTLD_LOCAL));
    if (handle_) {
      name_ = n;
      return;
    }
    const char* e = dlerror();
    tried += (tried.empty() ? "" : ", ") + std::string(n);
    why = e ? e : "unknown error";
  }
  throw std::runtime_error("cannot load " + tried + " (" + why + "); install the Debian package " +
                           package);
}

void* SharedLibrary::symbol(const char* name) const {
  dlerror();  // clear
  void* address = dlsym(handle_, name);
  if (!address)
    throw std::runtime_error(std::string("the shared library ") + name_ + " has no symbol " + name);
  return address;
}

}  // namespace orthomech::detail

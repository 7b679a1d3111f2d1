// src/io/shared_library.cpp: a library opened at run time, its functions typed by their
// declarations, and the messages when a library or a symbol is missing. Oracle: the same function
// of the C library linked at build time (cos), and the names the messages must carry.
#include "../../../src/io/shared_library.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace orthomech {
namespace {

TEST(SharedLibrary, AFunctionOpenedAtRunTimeIsTheLinkedOne) {
  const detail::SharedLibrary libm({"libm-not-here.so.9", "libm.so.6"}, false, "libc6");
  EXPECT_EQ(libm.name(), "libm.so.6");  // the first name that loads
  double (*const cosine)(double) = libm.function<double(double)>("cos");
  for (const double x : {0.0, 0.5, 2.0, -7.25}) EXPECT_EQ(cosine(x), std::cos(x)) << x;
}

TEST(SharedLibrary, AMissingLibraryNamesItsNamesAndThePackage) {
  try {
    const detail::SharedLibrary lib({"liborthomech-absent.so.1", "liborthomech-absent.so.2"}, false,
                                    "orthomech-absent");
    ADD_FAILURE() << "opened " << lib.name();
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("liborthomech-absent.so.1, liborthomech-absent.so.2"), std::string::npos) << m;
    EXPECT_NE(m.find("install the Debian package orthomech-absent"), std::string::npos) << m;
  }
}

TEST(SharedLibrary, AMissingSymbolNamesItAndTheLibrary) {
  const detail::SharedLibrary libm({"libm.so.6"}, false, "libc6");
  try {
    (void)libm.symbol("orthomech_no_such_symbol");
    ADD_FAILURE() << "found";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "the shared library libm.so.6 has no symbol orthomech_no_such_symbol");
  }
}

}  // namespace
}  // namespace orthomech

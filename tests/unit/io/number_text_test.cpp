// append_number / number_text (include/orthomech/io/number_text.hpp) against their oracle,
// printf's "%.Pg" (std::snprintf in the "C" locale), character for character: random doubles
// over the whole exponent range, both signs, every precision 1 … 17, and the edge cases — ±0,
// ±∞, NaN, subnormals, the largest and smallest normal numbers, powers of ten and values that
// round up to the next power of ten (9.9999…).
#include "orthomech/io/number_text.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace orthomech {
namespace {

std::string printf_g(double v, int precision) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", precision, v);
  return buf;
}

TEST(NumberText, EqualsPrintfOnRandomDoublesAtEveryPrecision) {
  std::mt19937_64 gen(2026);
  std::uniform_int_distribution<unsigned long long> bits;
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-30, 30);
  int compared = 0;
  for (int i = 0; i < 20000; ++i) {
    double v = 0.0;
    if (i % 2 == 0) {  // any bit pattern: the whole exponent range, subnormals, NaNs
      const unsigned long long b = bits(gen);
      std::memcpy(&v, &b, sizeof v);
    } else {  // the magnitudes the outputs hold
      v = unit(gen) * std::pow(10.0, exponent(gen));
    }
    for (int p = 1; p <= 17; ++p) {
      std::string s;
      append_number(s, v, p);
      if (std::isnan(v)) {  // printf's text of a NaN is "nan" or "-nan", as to_chars's
        EXPECT_TRUE(s == "nan" || s == "-nan") << s;
        EXPECT_EQ(s, printf_g(v, p));
        continue;
      }
      ASSERT_EQ(s, printf_g(v, p)) << "precision " << p;
      ++compared;
    }
  }
  // 20 000 values × 17 precisions = 340 000 texts, less the NaNs' (random bit patterns are NaN
  // with probability 2⁻¹¹, and their texts are checked above instead).
  EXPECT_GT(compared, 300000);
}

TEST(NumberText, EqualsPrintfOnTheEdgeCases) {
  using L = std::numeric_limits<double>;
  const std::vector<double> values = {0.0,
                                      -0.0,
                                      L::infinity(),
                                      -L::infinity(),
                                      L::quiet_NaN(),
                                      L::denorm_min(),
                                      -L::denorm_min(),
                                      L::min(),
                                      L::max(),
                                      -L::max(),
                                      L::epsilon(),
                                      1.0,
                                      10.0,
                                      1e-5,
                                      1e-4,
                                      123456789012.0,
                                      1234567890123.0,
                                      9.99999999999951,
                                      0.000099999999999999,
                                      99999999999.99,
                                      0.5,
                                      2.5,
                                      1.0 / 3.0};
  for (const double v : values)
    for (int p = 1; p <= 17; ++p) EXPECT_EQ(number_text(v, p), printf_g(v, p)) << v << " " << p;
  EXPECT_EQ(number_text(-0.0, 12), "-0");
  EXPECT_EQ(number_text(9.99999999999951, 12), "10");
  EXPECT_EQ(number_text(1e-5, 12), "1e-05");
}

TEST(NumberText, AppendsAndRefusesAPrecisionOutOfRange) {
  std::string s = "t,";
  append_number(s, 0.25, 12);
  s += ',';
  append_number(s, -1.5e300, 3);
  EXPECT_EQ(s, "t,0.25,-1.5e+300");
  EXPECT_THROW(append_number(s, 1.0, 0), std::invalid_argument);
  EXPECT_THROW(append_number(s, 1.0, 18), std::invalid_argument);
}

}  // namespace
}  // namespace orthomech

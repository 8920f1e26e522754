// Tests of the exact predicates (src/geometry/predicates.cpp) against an exact big-integer
// oracle (tests/support/exact.h): random inputs in several ranges, adversarial near-degenerate
// inputs (ulp perturbations, nextafter grids after Kettner et al., "Classroom examples of
// robustness problems in geometric computations", 2008), exactly degenerate inputs from small
// integers and from float32 values, magnitudes near the documented range limits, and
// permutation symmetry. Every sign is compared with the oracle; none may differ.
// All random streams are std::mt19937_64 with fixed seeds, and doubles are made from its raw
// bits (not std::uniform_real_distribution), so every standard library sees the same inputs.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "splintcore/geometry.h"
#include "support/exact.h"

// The inputs below are built with floating-point arithmetic (a + s (b - a), ...): keep it free
// of FMA contraction even in a build without -ffp-contract=off, so every compiler and target
// tests the same inputs (ResultBitsArePinned depends on it).
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif

namespace {

using splintcore::collinear3d;
using splintcore::incircle;
using splintcore::orient2d;
using splintcore::orient3d;
using splintcore::sign_of;
using splintcore::Vec3;
using splintcore_test::BigInt;
using splintcore_test::exact_collinear3d;
using splintcore_test::exact_orient2d_sign;
using splintcore_test::exact_orient3d_sign;
using splintcore_test::to_common_scale;

// ---- deterministic random inputs ------------------------------------------------------------

class Rng {
 public:
  explicit Rng(uint64_t seed) : engine_(seed) {}
  // Uniform in [0, 1) from 53 random bits.
  double unit() { return static_cast<double>(engine_() >> 11) * 0x1p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  // Uniform integer in [lo, hi] (modulo bias is irrelevant here).
  int64_t integer(int64_t lo, int64_t hi) {
    // In unsigned arithmetic (no signed overflow for wide ranges); the result is in [lo, hi].
    const uint64_t span = static_cast<uint64_t>(hi) - static_cast<uint64_t>(lo) + 1u;
    return static_cast<int64_t>(static_cast<uint64_t>(lo) + engine_() % span);
  }
  int small(int lo, int hi) { return static_cast<int>(integer(lo, hi)); }
  double float32(double lo, double hi) {
    return static_cast<double>(static_cast<float>(uniform(lo, hi)));
  }
  bool coin() { return (engine_() >> 63) != 0; }
  // The helpers below draw in a fixed order (the order in which the arguments of one call are
  // evaluated is unspecified, and differs between g++ and clang++: every test input would
  // then depend on the compiler).
  // k 2^e with k uniform in [kmin, kmax] (drawn first), e in [emin, emax]: exact.
  double dyadic(int kmin, int kmax, int emin, int emax) {
    const int k = small(kmin, kmax);
    const int e = small(emin, emax);
    return std::ldexp(static_cast<double>(k), e);
  }
  // Random sign (drawn first) times uniform in [lo, hi).
  double signed_uniform(double lo, double hi) {
    const double sign = coin() ? 1.0 : -1.0;
    return sign * uniform(lo, hi);
  }

 private:
  std::mt19937_64 engine_;
};

enum class Range { kUnit, kMillimetre, kFloat32, kWideExponent, kSmallInteger, kClustered };
constexpr Range kAllRanges[] = {Range::kUnit,         Range::kMillimetre,   Range::kFloat32,
                                Range::kWideExponent, Range::kSmallInteger, Range::kClustered};

const char* range_name(Range r) {
  switch (r) {
    case Range::kUnit: return "[-1,1]";
    case Range::kMillimetre: return "[-1e3,1e3]";
    case Range::kFloat32: return "float32 [-1e3,1e3]";
    case Range::kWideExponent: return "+-[1,2)*2^[-40,40]";
    case Range::kSmallInteger: return "integers [-8,8]";
    case Range::kClustered: return "123.456 +- 1e-9";
  }
  return "?";
}

double random_coordinate(Rng& rng, Range r) {
  switch (r) {
    case Range::kUnit: return rng.uniform(-1.0, 1.0);
    case Range::kMillimetre: return rng.uniform(-1e3, 1e3);
    case Range::kFloat32: return rng.float32(-1e3, 1e3);
    case Range::kWideExponent: {
      const double m = rng.uniform(1.0, 2.0);
      const int e = rng.small(-40, 40);
      const double v = std::ldexp(m, e);  // exact
      return rng.coin() ? -v : v;
    }
    case Range::kSmallInteger: return static_cast<double>(rng.small(-8, 8));
    case Range::kClustered: return 123.456 + rng.uniform(-1e-9, 1e-9);
  }
  return 0.0;
}

// The ranges used for the "points on a line/plane" constructions.
double line_coordinate(Rng& rng, int kind) {
  switch (kind % 3) {
    case 0: return rng.uniform(-1.0, 1.0);
    case 1: return rng.uniform(-1e3, 1e3);
    default: return rng.float32(-1e3, 1e3);
  }
}

Vec3 random_point(Rng& rng, Range r) {
  return {random_coordinate(rng, r), random_coordinate(rng, r), random_coordinate(rng, r)};
}

// x moved by k ulps (k > 0 up, k < 0 down).
double ulps(double x, int k) {
  const double toward =
      k > 0 ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  for (int i = 0; i < (k > 0 ? k : -k); ++i) x = std::nextafter(x, toward);
  return x;
}

// The 64 values x - 32 ulps .. x + 31 ulps, in order.
std::vector<double> ulp_row(double x) {
  std::vector<double> row(64);
  double v = ulps(x, -32);
  for (double& r : row) {
    r = v;
    v = std::nextafter(v, std::numeric_limits<double>::infinity());
  }
  return row;
}

// ---- the naive formulas (to show that the inputs are hard) --------------------------------

int naive_orient2d_sign(double ax, double ay, double bx, double by, double cx, double cy) {
  return sign_of((ax - cx) * (by - cy) - (ay - cy) * (bx - cx));
}

int naive_orient3d_sign(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 ad = a - d;
  const Vec3 bd = b - d;
  const Vec3 cd = c - d;
  return sign_of(ad.x * (bd.y * cd.z - bd.z * cd.y) - ad.y * (bd.x * cd.z - bd.z * cd.x) +
                 ad.z * (bd.x * cd.y - bd.y * cd.x));
}

// ---- checking against the oracle -----------------------------------------------------------

std::string hex(double v) {
  std::ostringstream s;
  s << std::hexfloat << v;
  return s.str();
}
std::string hex(const Vec3& p) { return "(" + hex(p.x) + ", " + hex(p.y) + ", " + hex(p.z) + ")"; }

struct Tally {
  std::string name;
  int64_t cases = 0;
  int64_t wrong = 0;        // predicate sign differs from the oracle
  int64_t naive_wrong = 0;  // naive double formula sign differs from the oracle
  int64_t zeros = 0;        // oracle says exactly degenerate

  explicit Tally(std::string n) : name(std::move(n)) {}
  void print() const {
    std::printf("[   info   ] %-44s %8lld cases, %lld wrong, naive wrong %lld, exact zeros %lld\n",
                name.c_str(), static_cast<long long>(cases), static_cast<long long>(wrong),
                static_cast<long long>(naive_wrong), static_cast<long long>(zeros));
  }
};

int check2d(Tally& t, double ax, double ay, double bx, double by, double cx, double cy) {
  const int expected = exact_orient2d_sign(ax, ay, bx, by, cx, cy);
  const int got = sign_of(orient2d(ax, ay, bx, by, cx, cy));
  ++t.cases;
  if (expected == 0) ++t.zeros;
  if (naive_orient2d_sign(ax, ay, bx, by, cx, cy) != expected) ++t.naive_wrong;
  if (got != expected && ++t.wrong <= 5) {
    ADD_FAILURE() << t.name << ": orient2d(" << hex(ax) << ", " << hex(ay) << ", " << hex(bx)
                  << ", " << hex(by) << ", " << hex(cx) << ", " << hex(cy) << ") has sign " << got
                  << ", exact sign " << expected;
  }
  return expected;
}

int check3d(Tally& t, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const int expected = exact_orient3d_sign(a, b, c, d);
  const int got = sign_of(orient3d(a, b, c, d));
  ++t.cases;
  if (expected == 0) ++t.zeros;
  if (naive_orient3d_sign(a, b, c, d) != expected) ++t.naive_wrong;
  if (got != expected && ++t.wrong <= 5) {
    ADD_FAILURE() << t.name << ": orient3d(" << hex(a) << ", " << hex(b) << ", " << hex(c) << ", "
                  << hex(d) << ") has sign " << got << ", exact sign " << expected;
  }
  return expected;
}

// ---- the oracle itself ----------------------------------------------------------------------

TEST(ExactOracle, BigIntMatchesInt64AndAlgebra) {
  Rng rng(11);
  for (int i = 0; i < 20000; ++i) {
    const int64_t a = rng.integer(-(int64_t{1} << 31), int64_t{1} << 31);
    const int64_t b = rng.integer(-(int64_t{1} << 31), int64_t{1} << 31);
    ASSERT_TRUE(BigInt(a) * BigInt(b) == BigInt(a * b)) << a << " * " << b;
    ASSERT_TRUE(BigInt(a) + BigInt(b) == BigInt(a + b)) << a << " + " << b;
    ASSERT_TRUE(BigInt(a) - BigInt(b) == BigInt(a - b)) << a << " - " << b;
    ASSERT_EQ(compare(BigInt(a), BigInt(b)), (a > b) - (a < b));
    ASSERT_EQ(BigInt(a).sign(), (a > 0) - (a < 0));
  }
  for (int i = 0; i < 2000; ++i) {
    const int64_t m = rng.integer(0, int64_t{1} << 62);
    const unsigned shift = static_cast<unsigned>(rng.small(0, 200));
    const bool negative = rng.coin();
    const BigInt expected = (negative ? -BigInt(m) : BigInt(m)).shifted_left(shift);
    ASSERT_TRUE(BigInt::from_magnitude(static_cast<uint64_t>(m), shift, negative) == expected);
    ASSERT_TRUE(BigInt(m).shifted_left(shift) == BigInt(m) * BigInt(1).shifted_left(shift));
  }
  // (2^64 - 1)(2^64 + 1) = 2^128 - 1, and carries across many limbs.
  const BigInt one(1);
  const BigInt p64 = one.shifted_left(64);
  EXPECT_TRUE((p64 - one) * (p64 + one) == one.shifted_left(128) - one);
  EXPECT_TRUE(one.shifted_left(1000) - one + one == one.shifted_left(1000));
  EXPECT_EQ((one - one.shifted_left(500)).sign(), -1);
  // Ring identities on multi-limb values of mixed signs.
  for (int i = 0; i < 2000; ++i) {
    auto big = [&rng]() {
      BigInt v(rng.integer(-(int64_t{1} << 62), int64_t{1} << 62));
      return v.shifted_left(static_cast<unsigned>(rng.small(0, 300))) +
             BigInt(rng.integer(-1000000, 1000000));
    };
    const BigInt x = big();
    const BigInt y = big();
    const BigInt z = big();
    ASSERT_TRUE((x * y) * z == x * (y * z));
    ASSERT_TRUE(x * (y + z) == x * y + x * z);
    ASSERT_TRUE((x + y) - y == x);
    ASSERT_TRUE(x - x == BigInt());
    ASSERT_EQ((x * y).sign(), x.sign() * y.sign());
  }
}

TEST(ExactOracle, DecomposeIsExactAndOrderPreserving) {
  Rng rng(12);
  const double specials[] = {0.0,
                             -0.0,
                             1.0,
                             -1.0,
                             0.5,
                             std::numeric_limits<double>::min(),
                             std::numeric_limits<double>::denorm_min(),
                             std::numeric_limits<double>::max(),
                             -std::numeric_limits<double>::max()};
  for (double v : specials) {
    const splintcore_test::DyadicParts p = splintcore_test::decompose(v);
    EXPECT_EQ(std::ldexp(static_cast<double>(p.mantissa), p.exponent), v) << hex(v);
  }
  for (int i = 0; i < 20000; ++i) {
    const Range r = kAllRanges[i % 6];
    const double x = random_coordinate(rng, r);
    const double y = rng.coin() ? random_coordinate(rng, r) : ulps(x, rng.small(-2, 2));
    const splintcore_test::DyadicParts p = splintcore_test::decompose(x);
    ASSERT_EQ(std::ldexp(static_cast<double>(p.mantissa), p.exponent), x) << hex(x);
    const double v[2] = {x, y};
    const std::vector<BigInt> n = splintcore_test::to_common_scale(v, 2);
    ASSERT_EQ(compare(n[0], n[1]), (x > y) - (x < y)) << hex(x) << " " << hex(y);
  }
  EXPECT_TRUE(splintcore_test::exact_sum_is(1.0, 0x1p-52, 1.0 + 0x1p-52));
  EXPECT_FALSE(splintcore_test::exact_sum_is(1.0, 0x1p-54, 1.0 + 0x1p-54));
}

// ---- simple exact cases --------------------------------------------------------------------

TEST(Predicates, SimpleExactCases) {
  // Unit triangle, both ways.
  EXPECT_GT(orient2d(0, 0, 1, 0, 0, 1), 0.0);
  EXPECT_LT(orient2d(0, 0, 0, 1, 1, 0), 0.0);
  EXPECT_EQ(orient2d(0, 0, 1, 0, 0, 1), 1.0);  // fast path: the exact value
  // Collinear and coincident points: exactly zero.
  EXPECT_EQ(orient2d(0, 0, 1, 1, 2, 2), 0.0);
  EXPECT_EQ(orient2d(1, 2, 1, 2, 5, -7), 0.0);
  EXPECT_EQ(orient2d(3, 3, 3, 3, 3, 3), 0.0);
  EXPECT_EQ(orient2d(0.1, 0.1, 0.2, 0.2, 0.3, 0.3), 0.0);  // all three lie on y = x exactly
  // Kettner et al.'s first example: p, q, r on y = x.
  EXPECT_EQ(orient2d(0.5, 0.5, 12, 12, 24, 24), 0.0);

  const Vec3 o{0, 0, 0};
  const Vec3 ex{1, 0, 0};
  const Vec3 ey{0, 1, 0};
  // a, b, c counter-clockwise seen from above; d below the plane gives > 0, above < 0.
  EXPECT_GT(orient3d(o, ex, ey, Vec3{0, 0, -1}), 0.0);
  EXPECT_LT(orient3d(o, ex, ey, Vec3{0, 0, 1}), 0.0);
  EXPECT_EQ(orient3d(o, ex, ey, Vec3{0, 0, -1}), 1.0);
  EXPECT_LT(orient3d(o, ey, ex, Vec3{0, 0, -1}), 0.0);
  // Coplanar and degenerate: exactly zero.
  EXPECT_EQ(orient3d(o, ex, ey, Vec3{0.3, 0.7, 0}), 0.0);
  EXPECT_EQ(orient3d(Vec3{1, 2, 3}, Vec3{4, 5, 6}, Vec3{7, 8, 9}, Vec3{-1, 0.5, 2}), 0.0);
  EXPECT_EQ(orient3d(ex, ex, ey, Vec3{5, 5, 5}), 0.0);
  EXPECT_EQ(
      orient3d(Vec3{0.1, 0.2, 0.3}, Vec3{0.1, 0.2, 0.3}, Vec3{0.1, 0.2, 0.3}, Vec3{0.1, 0.2, 0.3}),
      0.0);
  // Points of the plane x + y + z = 1 written in decimal: after rounding to binary they are
  // only nearly coplanar, so the sign is whatever the oracle says.
  const Vec3 p{0.1, 0.2, 0.7};
  const Vec3 q{0.3, 0.3, 0.4};
  const Vec3 r{0.6, 0.1, 0.3};
  const Vec3 s{0.2, 0.5, 0.3};
  EXPECT_EQ(sign_of(orient3d(p, q, r, s)), exact_orient3d_sign(p, q, r, s));

  EXPECT_TRUE(collinear3d(o, ex, Vec3{2, 0, 0}));
  EXPECT_TRUE(collinear3d(o, o, o));
  EXPECT_TRUE(collinear3d(ex, ex, ey));
  EXPECT_TRUE(collinear3d(Vec3{1, 2, 3}, Vec3{2, 4, 6}, Vec3{-3, -6, -9}));
  EXPECT_FALSE(collinear3d(o, ex, ey));
  EXPECT_FALSE(collinear3d(Vec3{1, 2, 3}, Vec3{2, 4, 6}, Vec3{-3, -6, -8}));
}

// ---- random inputs -------------------------------------------------------------------------

constexpr int kRandomPerRange = 40000;  // x 6 ranges = 240,000 per predicate

TEST(Predicates, Orient2dRandomMatchesOracle) {
  int64_t total = 0;
  for (Range r : kAllRanges) {
    Tally t(std::string("orient2d random ") + range_name(r));
    Rng rng(1000 + static_cast<uint64_t>(r));
    for (int i = 0; i < kRandomPerRange; ++i) {
      const double ax = random_coordinate(rng, r), ay = random_coordinate(rng, r);
      const double bx = random_coordinate(rng, r), by = random_coordinate(rng, r);
      const double cx = random_coordinate(rng, r), cy = random_coordinate(rng, r);
      check2d(t, ax, ay, bx, by, cx, cy);
    }
    t.print();
    EXPECT_EQ(t.wrong, 0) << t.name;
    total += t.cases;
  }
  EXPECT_GE(total, 200000);
}

TEST(Predicates, Orient3dRandomMatchesOracle) {
  int64_t total = 0;
  for (Range r : kAllRanges) {
    Tally t(std::string("orient3d random ") + range_name(r));
    Rng rng(2000 + static_cast<uint64_t>(r));
    for (int i = 0; i < kRandomPerRange; ++i) {
      const Vec3 a = random_point(rng, r);
      const Vec3 b = random_point(rng, r);
      const Vec3 c = random_point(rng, r);
      const Vec3 d = random_point(rng, r);
      check3d(t, a, b, c, d);
    }
    t.print();
    EXPECT_EQ(t.wrong, 0) << t.name;
    total += t.cases;
  }
  EXPECT_GE(total, 200000);
}

// ---- adversarial orient2d ------------------------------------------------------------------

struct Point2 {
  double x;
  double y;
};

// Kettner-style sweep: one of the three points moves over a 64 x 64 grid of nextafter steps
// around its position, the others stay. `scale` (a power of two, so exact) moves the whole
// configuration to other magnitudes.
void sweep2d(Tally& t, Point2 p[3], int moving, double scale = 1.0) {
  for (int i = 0; i < 3; ++i) {
    p[i].x *= scale;
    p[i].y *= scale;
  }
  const std::vector<double> xs = ulp_row(p[moving].x);
  const std::vector<double> ys = ulp_row(p[moving].y);
  Point2 q[3] = {p[0], p[1], p[2]};
  for (double x : xs) {
    for (double y : ys) {
      q[moving] = {x, y};
      check2d(t, q[0].x, q[0].y, q[1].x, q[1].y, q[2].x, q[2].y);
    }
  }
}

// Three nearly collinear points: a, b random, c = a + s (b - a) rounded.
void near_line(Rng& rng, int kind, Point2 p[3]) {
  p[0] = {line_coordinate(rng, kind), line_coordinate(rng, kind)};
  p[1] = {line_coordinate(rng, kind), line_coordinate(rng, kind)};
  const double s = rng.uniform(-2.0, 3.0);
  p[2] = {p[0].x + s * (p[1].x - p[0].x), p[0].y + s * (p[1].y - p[0].y)};
}

TEST(Predicates, Orient2dNearDegenerateGridsMatchOracle) {
  Tally t("orient2d nextafter grids 64x64");
  // Kettner et al. 2008, the three configurations of their Figure 2.
  Point2 k1[3] = {{0.5, 0.5}, {12, 12}, {24, 24}};
  Point2 k2[3] = {{0.50000000000002531, 0.5000000000000171},
                  {17.300000000000001, 17.300000000000001},
                  {24.00000000000005, 24.0000000000000053}};
  Point2 k3[3] = {{0.5, 0.5}, {8.8000000000000007, 7.7000000000000002}, {12.1, 12.1}};
  sweep2d(t, k1, 0);
  sweep2d(t, k2, 0);
  sweep2d(t, k3, 0);
  Rng rng(3001);
  for (int config = 0; config < 29; ++config) {
    Point2 p[3];
    near_line(rng, config, p);
    sweep2d(t, p, config % 3);
  }
  t.print();
  EXPECT_EQ(t.wrong, 0);
  EXPECT_GE(t.cases, 32 * 4096);
  EXPECT_GT(t.naive_wrong, 0) << "the grids must be hard for the naive formula";
  EXPECT_GT(t.zeros, 0) << "the grids cross the line";
}

TEST(Predicates, Orient2dNearDegenerateLinesMatchOracle) {
  // Points on a line, rounded, then perturbed by a few ulps.
  Tally perturbed("orient2d on a line +- 3 ulps");
  Rng rng(3002);
  for (int i = 0; i < 60000; ++i) {
    Point2 p[3];
    near_line(rng, i, p);
    for (Point2& q : p) {
      if (rng.coin()) q.x = ulps(q.x, rng.small(-3, 3));
      if (rng.coin()) q.y = ulps(q.y, rng.small(-3, 3));
    }
    check2d(perturbed, p[0].x, p[0].y, p[1].x, p[1].y, p[2].x, p[2].y);
  }
  perturbed.print();
  EXPECT_EQ(perturbed.wrong, 0);
  EXPECT_GT(perturbed.naive_wrong, 0);

  // base + k * tiny * direction, rounded, with k of very different sizes (1 to 2^40), so
  // that the points are far apart in ulps and their differences are not exact.
  Tally steps("orient2d base + k * tiny along a line");
  for (int i = 0; i < 40000; ++i) {
    const double bx = line_coordinate(rng, i);
    const double by = line_coordinate(rng, i);
    const double dx = rng.uniform(-1.0, 1.0);
    const double dy = rng.uniform(-1.0, 1.0);
    const double tiny = std::ldexp(1.0, -rng.small(10, 50));
    double c[6];
    for (int j = 0; j < 3; ++j) {
      const double k = rng.dyadic(-1000, 1000, 0, 40);
      c[2 * j] = bx + (k * tiny) * dx;
      c[2 * j + 1] = by + (k * tiny) * dy;
    }
    check2d(steps, c[0], c[1], c[2], c[3], c[4], c[5]);
  }
  steps.print();
  EXPECT_EQ(steps.wrong, 0);
  EXPECT_GT(steps.naive_wrong, 0);
}

TEST(Predicates, Orient2dExactlyDegenerateIsZero) {
  Rng rng(3003);
  // Small integers: a + k d, scaled by a power of two (exact).
  Tally ints("orient2d exactly collinear integers");
  for (int i = 0; i < 30000; ++i) {
    const double scale = std::ldexp(1.0, rng.small(-60, 60));
    const double ax = static_cast<double>(rng.small(-1000, 1000));
    const double ay = static_cast<double>(rng.small(-1000, 1000));
    const double dx = static_cast<double>(rng.small(-1000, 1000));
    const double dy = static_cast<double>(rng.small(-1000, 1000));
    double c[6];
    for (int j = 0; j < 3; ++j) {
      const double k = static_cast<double>(rng.small(-100, 100));
      c[2 * j] = (ax + k * dx) * scale;
      c[2 * j + 1] = (ay + k * dy) * scale;
    }
    ASSERT_EQ(check2d(ints, c[0], c[1], c[2], c[3], c[4], c[5]), 0);
    ASSERT_EQ(orient2d(c[0], c[1], c[2], c[3], c[4], c[5]), 0.0);
  }
  ints.print();
  EXPECT_EQ(ints.wrong, 0);

  // float32 points (as read from a binary STL): a = ma 2^ea, d = md 2^ed with 11-bit
  // mantissas and ea, ed in [-8, 0]; then a + k d (|k| <= 16) is a multiple of 2^-8 below
  // 2^16, so it is itself a float32, and the points are exactly collinear.
  Tally floats("orient2d exactly collinear float32");
  for (int i = 0; i < 30000; ++i) {
    auto f = [&rng]() { return rng.dyadic(-2047, 2047, -8, 0); };
    const double ax = f(), ay = f(), dx = f(), dy = f();
    double c[6];
    for (int j = 0; j < 3; ++j) {
      const double k = static_cast<double>(rng.small(-16, 16));
      c[2 * j] = ax + k * dx;
      c[2 * j + 1] = ay + k * dy;
    }
    for (double v : c) ASSERT_EQ(static_cast<double>(static_cast<float>(v)), v);
    ASSERT_EQ(check2d(floats, c[0], c[1], c[2], c[3], c[4], c[5]), 0);
    ASSERT_EQ(orient2d(c[0], c[1], c[2], c[3], c[4], c[5]), 0.0);
  }
  floats.print();
  EXPECT_EQ(floats.wrong, 0);

  // Exactly collinear points whose differences are NOT exact in double: (m2 s, m1 s) on the
  // line through the origin with direction (m2, m1), s = k 2^e with e spread over [-40, 40].
  // This reaches the last stage with nonzero tails and an exact zero to find.
  Tally spread("orient2d exactly collinear, inexact differences");
  for (int i = 0; i < 30000; ++i) {
    const double m1 = static_cast<double>(rng.small(-7, 7));
    const double m2 = static_cast<double>(rng.small(-7, 7));
    double c[6];
    for (int j = 0; j < 3; ++j) {
      const double sj = rng.dyadic(-(1 << 20), 1 << 20, -40, 40);
      c[2 * j] = m2 * sj;  // exact: at most 23 significant bits
      c[2 * j + 1] = m1 * sj;
    }
    ASSERT_EQ(check2d(spread, c[0], c[1], c[2], c[3], c[4], c[5]), 0);
    ASSERT_EQ(orient2d(c[0], c[1], c[2], c[3], c[4], c[5]), 0.0);
  }
  spread.print();
  EXPECT_EQ(spread.wrong, 0);
}

TEST(Predicates, Orient2dNearRangeLimitsMatchOracle) {
  // The documented range is 2^-485 <= |x| <= 2^509 for nonzero coordinates.
  // 1. Grids scaled by powers of two (exact) to both ends: coordinates in [1.5, 2^10) before
  //    scaling, so in [2^-485, 2^509) after (the +-32 ulp steps stay inside).
  Tally t("orient2d grids scaled by 2^499 and 2^-485");
  Rng rng(3004);
  for (int config = 0; config < 8; ++config) {
    Point2 p[3];
    bool ok = false;
    while (!ok) {
      near_line(rng, 1, p);
      ok = true;
      for (const Point2& q : p) {
        ok = ok && std::fabs(q.x) >= 1.5 && std::fabs(q.x) < 1024 && std::fabs(q.y) >= 1.5 &&
             std::fabs(q.y) < 1024;
      }
    }
    sweep2d(t, p, config % 3, std::ldexp(1.0, config % 2 == 0 ? 499 : -485));
  }
  t.print();
  EXPECT_EQ(t.wrong, 0);
  EXPECT_GT(t.naive_wrong, 0);

  // 2. Clusters of points a few ulps apart at the low end: the differences are a few units of
  //    2^-537 and their products are subnormal (down to 2^-1074), as are the error bounds.
  Tally cluster("orient2d ulp clusters at 2^-485");
  for (int i = 0; i < 20000; ++i) {
    const double scale = 0x1p-485;
    const double bx = rng.signed_uniform(1.5, 2.0) * scale;
    const double by = rng.signed_uniform(1.5, 2.0) * scale;
    double c[6];
    for (int j = 0; j < 3; ++j) {
      c[2 * j] = ulps(bx, rng.small(-32, 32));
      c[2 * j + 1] = ulps(by, rng.small(-32, 32));
    }
    check2d(cluster, c[0], c[1], c[2], c[3], c[4], c[5]);
  }
  cluster.print();
  EXPECT_EQ(cluster.wrong, 0);
  EXPECT_GT(cluster.zeros, 0);
}

// ---- adversarial orient3d ------------------------------------------------------------------

// Four nearly coplanar points: a, b, c random, d = a + s (b - a) + u (c - a) rounded.
void near_plane(Rng& rng, int kind, Vec3 p[4]) {
  for (int i = 0; i < 3; ++i) {
    p[i] = {line_coordinate(rng, kind), line_coordinate(rng, kind), line_coordinate(rng, kind)};
  }
  const double s = rng.uniform(-1.0, 2.0);
  const double u = rng.uniform(-1.0, 2.0);
  p[3] = p[0] + s * (p[1] - p[0]) + u * (p[2] - p[0]);
}

// One point moves over a 64 x 64 grid of nextafter steps in two of its coordinates.
void sweep3d(Tally& t, Vec3 p[4], int moving, int axis, double scale = 1.0) {
  for (int i = 0; i < 4; ++i) p[i] = p[i] * scale;
  const int axis2 = (axis + 1) % 3;
  const std::vector<double> us = ulp_row(p[moving][axis]);
  const std::vector<double> vs = ulp_row(p[moving][axis2]);
  Vec3 q[4] = {p[0], p[1], p[2], p[3]};
  for (double u : us) {
    for (double v : vs) {
      q[moving][axis] = u;
      q[moving][axis2] = v;
      check3d(t, q[0], q[1], q[2], q[3]);
    }
  }
}

TEST(Predicates, Orient3dNearDegenerateGridsMatchOracle) {
  Tally t("orient3d nextafter grids 64x64");
  Rng rng(4001);
  for (int config = 0; config < 32; ++config) {
    Vec3 p[4];
    near_plane(rng, config, p);
    sweep3d(t, p, config % 4, (config / 4) % 3);
  }
  t.print();
  EXPECT_EQ(t.wrong, 0);
  EXPECT_GE(t.cases, 32 * 4096);
  EXPECT_GT(t.naive_wrong, 0) << "the grids must be hard for the naive formula";
}

TEST(Predicates, Orient3dNearDegeneratePlanesMatchOracle) {
  Tally perturbed("orient3d on a plane +- 3 ulps");
  Rng rng(4002);
  for (int i = 0; i < 60000; ++i) {
    Vec3 p[4];
    near_plane(rng, i, p);
    for (Vec3& q : p) {
      for (int axis = 0; axis < 3; ++axis) {
        if (rng.coin()) q[axis] = ulps(q[axis], rng.small(-3, 3));
      }
    }
    check3d(perturbed, p[0], p[1], p[2], p[3]);
  }
  perturbed.print();
  EXPECT_EQ(perturbed.wrong, 0);
  EXPECT_GT(perturbed.naive_wrong, 0);

  // base + (i u + j v) * tiny, rounded, with i, j of very different sizes (1 to 2^40).
  Tally steps("orient3d base + (i u + j v) * tiny in a plane");
  for (int n = 0; n < 40000; ++n) {
    const Vec3 base{line_coordinate(rng, n), line_coordinate(rng, n), line_coordinate(rng, n)};
    const Vec3 u{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    const Vec3 v{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    const double tiny = std::ldexp(1.0, -rng.small(10, 50));
    Vec3 p[4];
    for (Vec3& q : p) {
      const int e = rng.small(0, 40);
      const double i = std::ldexp(static_cast<double>(rng.small(-1000, 1000)), e) * tiny;
      const double j = std::ldexp(static_cast<double>(rng.small(-1000, 1000)), e) * tiny;
      q = base + i * u + j * v;
    }
    check3d(steps, p[0], p[1], p[2], p[3]);
  }
  steps.print();
  EXPECT_EQ(steps.wrong, 0);
  EXPECT_GT(steps.naive_wrong, 0);
}

TEST(Predicates, Orient3dExactlyDegenerateIsZero) {
  Rng rng(4003);
  Tally ints("orient3d exactly coplanar integers");
  for (int n = 0; n < 30000; ++n) {
    const double scale = std::ldexp(1.0, rng.small(-60, 60));
    auto coordinate = [&rng](int range) { return static_cast<double>(rng.small(-range, range)); };
    const Vec3 a{coordinate(1000), coordinate(1000), coordinate(1000)};
    const Vec3 u{coordinate(100), coordinate(100), coordinate(100)};
    // Every third case: a, b, c collinear too (v parallel to u), d anywhere in space.
    const bool collinear = n % 3 == 0;
    const Vec3 v = collinear ? u * 3.0 : Vec3{coordinate(100), coordinate(100), coordinate(100)};
    Vec3 p[4];
    for (Vec3& q : p) {
      const double i = coordinate(20);
      const double j = coordinate(20);
      q = (a + i * u + j * v) * scale;
    }
    if (collinear) p[3] = Vec3{coordinate(1000), coordinate(1000), coordinate(1000)} * scale;
    ASSERT_EQ(check3d(ints, p[0], p[1], p[2], p[3]), 0);
    ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), 0.0);
  }
  ints.print();
  EXPECT_EQ(ints.wrong, 0);

  // float32 points: a + i u + j v with 10-bit mantissas, exponents in [-8, 0], |i|, |j| <= 8:
  // multiples of 2^-8 below 2^15, so float32 values themselves.
  Tally floats("orient3d exactly coplanar float32");
  for (int n = 0; n < 30000; ++n) {
    auto f = [&rng]() { return rng.dyadic(-1023, 1023, -8, 0); };
    const Vec3 a{f(), f(), f()};
    const Vec3 u{f(), f(), f()};
    const Vec3 v{f(), f(), f()};
    Vec3 p[4];
    for (Vec3& q : p) {
      const double i = static_cast<double>(rng.small(-8, 8));
      const double j = static_cast<double>(rng.small(-8, 8));
      q = a + i * u + j * v;
      for (int axis = 0; axis < 3; ++axis) {
        ASSERT_EQ(static_cast<double>(static_cast<float>(q[axis])), q[axis]);
      }
    }
    ASSERT_EQ(check3d(floats, p[0], p[1], p[2], p[3]), 0);
    ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), 0.0);
  }
  floats.print();
  EXPECT_EQ(floats.wrong, 0);

  // Exactly coplanar points whose differences are NOT exact in double: on the plane
  // w = m1 u + m2 v through the origin (axes permuted), with u = k1 2^(E + r1),
  // v = k2 2^(E + r2), |k| <= 2^20, r in [0, 24], E in [-40, 40] per point: m1 u + m2 v is a
  // multiple of 2^E below 2^(E + 48), so exact, while differences between points are not.
  Tally spread("orient3d exactly coplanar, inexact differences");
  for (int n = 0; n < 30000; ++n) {
    const double m1 = static_cast<double>(rng.small(-7, 7));
    const double m2 = static_cast<double>(rng.small(-7, 7));
    const int axis = rng.small(0, 2);
    Vec3 p[4];
    for (Vec3& q : p) {
      const int e = rng.small(-40, 40);
      const double u = rng.dyadic(-(1 << 20), 1 << 20, e, e + 24);
      const double v = rng.dyadic(-(1 << 20), 1 << 20, e, e + 24);
      q[axis] = u;
      q[(axis + 1) % 3] = v;
      q[(axis + 2) % 3] = m1 * u + m2 * v;
      ASSERT_TRUE(splintcore_test::exact_sum_is(m1 * u, m2 * v, q[(axis + 2) % 3]));
    }
    ASSERT_EQ(check3d(spread, p[0], p[1], p[2], p[3]), 0);
    ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), 0.0);
  }
  spread.print();
  EXPECT_EQ(spread.wrong, 0);
}

TEST(Predicates, Orient3dNearRangeLimitsMatchOracle) {
  // The documented range is 2^-306 <= |x| <= 2^338 for nonzero coordinates.
  // 1. Grids scaled to both ends: coordinates in [1.5, 2^10) before scaling.
  Tally t("orient3d grids scaled by 2^328 and 2^-306");
  Rng rng(4004);
  for (int config = 0; config < 8; ++config) {
    Vec3 p[4];
    bool ok = false;
    while (!ok) {
      near_plane(rng, 1, p);
      ok = true;
      for (const Vec3& q : p) {
        for (int axis = 0; axis < 3; ++axis) {
          ok = ok && std::fabs(q[axis]) >= 1.5 && std::fabs(q[axis]) < 1024;
        }
      }
    }
    sweep3d(t, p, config % 4, config % 3, std::ldexp(1.0, config % 2 == 0 ? 328 : -306));
  }
  t.print();
  EXPECT_EQ(t.wrong, 0);
  EXPECT_GT(t.naive_wrong, 0);

  // 2. Clusters of points a few ulps apart at the low end: differences are a few units of
  //    2^-358, products of three of them subnormal (down to 2^-1074).
  Tally cluster("orient3d ulp clusters at 2^-306");
  for (int i = 0; i < 20000; ++i) {
    Vec3 base;
    for (int axis = 0; axis < 3; ++axis) {
      base[axis] = rng.signed_uniform(1.5, 2.0) * 0x1p-306;
    }
    Vec3 p[4];
    for (Vec3& q : p) {
      for (int axis = 0; axis < 3; ++axis) q[axis] = ulps(base[axis], rng.small(-8, 8));
    }
    check3d(cluster, p[0], p[1], p[2], p[3]);
  }
  cluster.print();
  EXPECT_EQ(cluster.wrong, 0);
  EXPECT_GT(cluster.zeros, 0);
}

// ---- symmetry ------------------------------------------------------------------------------

TEST(Predicates, Orient2dPermutationsChangeSignExactly) {
  Rng rng(5001);
  Tally t("orient2d permutation symmetry (base queries)");
  for (int i = 0; i < 30000; ++i) {
    Point2 p[3];
    near_line(rng, i, p);
    for (Point2& q : p) {
      if (rng.coin()) q.x = ulps(q.x, rng.small(-2, 2));
      if (rng.coin()) q.y = ulps(q.y, rng.small(-2, 2));
    }
    const Point2 a = p[0], b = p[1], c = p[2];
    const int s = check2d(t, a.x, a.y, b.x, b.y, c.x, c.y);
    // Transpositions negate, cyclic shifts keep.
    ASSERT_EQ(sign_of(orient2d(b.x, b.y, a.x, a.y, c.x, c.y)), -s);
    ASSERT_EQ(sign_of(orient2d(a.x, a.y, c.x, c.y, b.x, b.y)), -s);
    ASSERT_EQ(sign_of(orient2d(c.x, c.y, b.x, b.y, a.x, a.y)), -s);
    ASSERT_EQ(sign_of(orient2d(b.x, b.y, c.x, c.y, a.x, a.y)), s);
    ASSERT_EQ(sign_of(orient2d(c.x, c.y, a.x, a.y, b.x, b.y)), s);
  }
  t.print();
  EXPECT_EQ(t.wrong, 0);
}

TEST(Predicates, Orient3dPermutationsChangeSignExactly) {
  Rng rng(5002);
  Tally t("orient3d permutation symmetry (base queries)");
  for (int i = 0; i < 20000; ++i) {
    Vec3 p[4];
    near_plane(rng, i, p);
    for (Vec3& q : p) {
      for (int axis = 0; axis < 3; ++axis) {
        if (rng.coin()) q[axis] = ulps(q[axis], rng.small(-2, 2));
      }
    }
    const Vec3 a = p[0], b = p[1], c = p[2], d = p[3];
    const int s = check3d(t, a, b, c, d);
    // All six transpositions negate; an even permutation keeps.
    ASSERT_EQ(sign_of(orient3d(b, a, c, d)), -s);
    ASSERT_EQ(sign_of(orient3d(c, b, a, d)), -s);
    ASSERT_EQ(sign_of(orient3d(d, b, c, a)), -s);
    ASSERT_EQ(sign_of(orient3d(a, c, b, d)), -s);
    ASSERT_EQ(sign_of(orient3d(a, d, c, b)), -s);
    ASSERT_EQ(sign_of(orient3d(a, b, d, c)), -s);
    ASSERT_EQ(sign_of(orient3d(b, c, a, d)), s);
    ASSERT_EQ(sign_of(orient3d(b, a, d, c)), s);
  }
  t.print();
  EXPECT_EQ(t.wrong, 0);
}

// ---- determinism ---------------------------------------------------------------------------

uint64_t fold(uint64_t h, double v) {
  uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof(bits));
  return splintcore::hash_mix(h ^ bits);
}

// The returned values (not only their signs) over inputs that reach every stage, folded into
// one hash pinned here: g++ and clang++, -O0 and -O2, x86-64 and AArch64 must all give it.
// If the algorithm is changed on purpose, update the constant (the signs are checked above).
TEST(Predicates, ResultBitsArePinned) {
  uint64_t h2 = 0;
  uint64_t h3 = 0;
  Rng rng(7001);
  for (int config = 0; config < 6; ++config) {
    Point2 p[3];
    near_line(rng, config, p);
    const std::vector<double> xs = ulp_row(p[config % 3].x);
    const std::vector<double> ys = ulp_row(p[config % 3].y);
    for (size_t i = 0; i < 64; i += 3) {
      for (size_t j = 0; j < 64; j += 3) {
        p[config % 3] = {xs[i], ys[j]};
        h2 = fold(h2, orient2d(p[0].x, p[0].y, p[1].x, p[1].y, p[2].x, p[2].y));
      }
    }
    Vec3 q[4];
    near_plane(rng, config, q);
    const std::vector<double> us = ulp_row(q[config % 4].x);
    const std::vector<double> vs = ulp_row(q[config % 4].y);
    for (size_t i = 0; i < 64; i += 3) {
      for (size_t j = 0; j < 64; j += 3) {
        q[config % 4].x = us[i];
        q[config % 4].y = vs[j];
        h3 = fold(h3, orient3d(q[0], q[1], q[2], q[3]));
      }
    }
  }
  for (int i = 0; i < 2000; ++i) {
    const Range r = kAllRanges[i % 6];
    const double ax = random_coordinate(rng, r), ay = random_coordinate(rng, r);
    const double bx = random_coordinate(rng, r), by = random_coordinate(rng, r);
    const double cx = random_coordinate(rng, r), cy = random_coordinate(rng, r);
    h2 = fold(h2, orient2d(ax, ay, bx, by, cx, cy));
    const Vec3 a = random_point(rng, r);
    const Vec3 b = random_point(rng, r);
    const Vec3 c = random_point(rng, r);
    const Vec3 d = random_point(rng, r);
    h3 = fold(h3, orient3d(a, b, c, d));
  }
  std::printf("[   info   ] result hashes: orient2d 0x%016llx, orient3d 0x%016llx\n",
              static_cast<unsigned long long>(h2), static_cast<unsigned long long>(h3));
  EXPECT_EQ(h2, 0x1c678cec3804232eull);
  EXPECT_EQ(h3, 0x0612f7a795081a32ull);
}

// ---- collinear3d ---------------------------------------------------------------------------

TEST(Predicates, Collinear3dExactAndPerturbed) {
  Rng rng(6001);
  int64_t exact_cases = 0;
  int64_t perturbed_cases = 0;
  int64_t perturbed_false = 0;
  int64_t other_cases = 0;
  for (int n = 0; n < 20000; ++n) {
    Vec3 p[3];
    if (n % 2 == 0) {
      // Integers on a line, scaled by a power of two; some coincident points.
      const double scale = std::ldexp(1.0, rng.small(-60, 60));
      auto coordinate = [&rng](int range) { return static_cast<double>(rng.small(-range, range)); };
      const Vec3 a{coordinate(1000), coordinate(1000), coordinate(1000)};
      const Vec3 d = n % 10 == 0 ? Vec3{} : Vec3{coordinate(100), coordinate(100), coordinate(100)};
      for (Vec3& q : p) q = (a + coordinate(n % 6 == 0 ? 1 : 50) * d) * scale;
    } else {
      // float32 points on a line (as in Orient2dExactlyDegenerateIsZero).
      auto f = [&rng]() { return rng.dyadic(-2047, 2047, -8, 0); };
      const Vec3 a{f(), f(), f()};
      const Vec3 d{f(), f(), f()};
      for (Vec3& q : p) q = a + static_cast<double>(rng.small(-16, 16)) * d;
    }
    ASSERT_TRUE(exact_collinear3d(p[0], p[1], p[2]));
    ASSERT_TRUE(collinear3d(p[0], p[1], p[2])) << hex(p[0]) << " " << hex(p[1]) << " " << hex(p[2]);
    ASSERT_TRUE(collinear3d(p[2], p[0], p[1]));
    ++exact_cases;

    // One coordinate of one point moved by one ulp: usually no longer collinear.
    Vec3 q[3] = {p[0], p[1], p[2]};
    // (A zero coordinate would become a subnormal, outside the documented range: it moves to
    // +-2^-40 instead.)
    const int which = rng.small(0, 2);
    const int axis = rng.small(0, 2);
    const double old = q[which][axis];
    q[which][axis] =
        old != 0.0 ? ulps(old, rng.coin() ? 1 : -1) : (rng.coin() ? 0x1p-40 : -0x1p-40);
    const bool expected = exact_collinear3d(q[0], q[1], q[2]);
    ASSERT_EQ(collinear3d(q[0], q[1], q[2]), expected)
        << hex(q[0]) << " " << hex(q[1]) << " " << hex(q[2]);
    ++perturbed_cases;
    if (!expected) ++perturbed_false;
  }
  // Nearly collinear (rounded) and random triples.
  for (int n = 0; n < 20000; ++n) {
    Vec3 a, b, c;
    if (n % 2 == 0) {
      a = {line_coordinate(rng, n), line_coordinate(rng, n), line_coordinate(rng, n)};
      b = {line_coordinate(rng, n), line_coordinate(rng, n), line_coordinate(rng, n)};
      c = a + rng.uniform(-2.0, 3.0) * (b - a);
    } else {
      const Range r = kAllRanges[(n / 2) % 6];
      a = random_point(rng, r);
      b = random_point(rng, r);
      c = random_point(rng, r);
    }
    ASSERT_EQ(collinear3d(a, b, c), exact_collinear3d(a, b, c))
        << hex(a) << " " << hex(b) << " " << hex(c);
    ++other_cases;
  }
  std::printf(
      "[   info   ] collinear3d: %lld exactly collinear, %lld one-ulp perturbed (%lld not "
      "collinear), %lld near/random\n",
      static_cast<long long>(exact_cases), static_cast<long long>(perturbed_cases),
      static_cast<long long>(perturbed_false), static_cast<long long>(other_cases));
  EXPECT_GT(perturbed_false, perturbed_cases / 2);
}

// ---- incircle ------------------------------------------------------------------------------

// Sign of det[a - d, |a - d|^2; b - d, |b - d|^2; c - d, |c - d|^2], exactly (the oracle for
// incircle: the coordinates on one common integer scale, then integer arithmetic).
int exact_incircle_sign(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                        double dy) {
  const double v[8] = {ax, ay, bx, by, cx, cy, dx, dy};
  const std::vector<BigInt> n = to_common_scale(v, 8);
  const BigInt adx = n[0] - n[6], ady = n[1] - n[7];
  const BigInt bdx = n[2] - n[6], bdy = n[3] - n[7];
  const BigInt cdx = n[4] - n[6], cdy = n[5] - n[7];
  const BigInt alift = adx * adx + ady * ady;
  const BigInt blift = bdx * bdx + bdy * bdy;
  const BigInt clift = cdx * cdx + cdy * cdy;
  const BigInt det = alift * (bdx * cdy - bdy * cdx) + blift * (cdx * ady - adx * cdy) +
                     clift * (adx * bdy - bdx * ady);
  return det.sign();
}

int naive_incircle_sign(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                        double dy) {
  const double adx = ax - dx, ady = ay - dy, bdx = bx - dx, bdy = by - dy;
  const double cdx = cx - dx, cdy = cy - dy;
  return sign_of((adx * adx + ady * ady) * (bdx * cdy - bdy * cdx) +
                 (bdx * bdx + bdy * bdy) * (cdx * ady - adx * cdy) +
                 (cdx * cdx + cdy * cdy) * (adx * bdy - bdx * ady));
}

struct Circle4 {
  Point2 p[4];  // a, b, c, d
};

int check_incircle(Tally& t, const Circle4& q) {
  const Point2 *a = &q.p[0], *b = &q.p[1], *c = &q.p[2], *d = &q.p[3];
  const int expected = exact_incircle_sign(a->x, a->y, b->x, b->y, c->x, c->y, d->x, d->y);
  const int got = sign_of(incircle(a->x, a->y, b->x, b->y, c->x, c->y, d->x, d->y));
  ++t.cases;
  if (expected == 0) ++t.zeros;
  if (naive_incircle_sign(a->x, a->y, b->x, b->y, c->x, c->y, d->x, d->y) != expected) {
    ++t.naive_wrong;
  }
  if (got != expected && ++t.wrong <= 5) {
    ADD_FAILURE() << t.name << ": incircle(" << hex(a->x) << ", " << hex(a->y) << ", " << hex(b->x)
                  << ", " << hex(b->y) << ", " << hex(c->x) << ", " << hex(c->y) << ", "
                  << hex(d->x) << ", " << hex(d->y) << ") has sign " << got << ", exact sign "
                  << expected;
  }
  return expected;
}

// A point of the circle (cx, cy, r) from the rational parametrisation
// ((1 - t^2) / (1 + t^2), 2 t / (1 + t^2)), rounded: nearly on the circle.
Point2 on_circle(double cx, double cy, double r, double t) {
  const double den = 1.0 + t * t;
  return {cx + r * ((1.0 - t * t) / den), cy + r * ((2.0 * t) / den)};
}

// v rounded to float32. Through a volatile: g++ 12 at -O2 folds the pair of conversions
// (double)(float)x of two neighbouring fields into nothing when it vectorises them (SLP), so
// `p = {(double)(float)p.x, (double)(float)p.y}` keeps p unrounded.
double to_float32(double v) {
  const volatile float f = static_cast<float>(v);
  return static_cast<double>(f);
}

// Four nearly cocircular points (kind: unit, millimetre or float32 scale).
Circle4 near_circle(Rng& rng, int kind) {
  const double cx = line_coordinate(rng, kind);
  const double cy = line_coordinate(rng, kind);
  const double r = kind % 3 == 0 ? rng.uniform(0.01, 1.0) : rng.uniform(0.1, 500.0);
  Circle4 q;
  for (Point2& p : q.p) {
    const double t = rng.uniform(-3.0, 3.0);
    p = on_circle(cx, cy, r, t);
    if (kind % 3 == 2) p = {to_float32(p.x), to_float32(p.y)};
  }
  return q;
}

TEST(Predicates, IncircleSimpleExactCases) {
  // The unit square's circle: the centre is inside, far points outside, corners on it.
  EXPECT_GT(incircle(0, 0, 1, 0, 1, 1, 0.5, 0.5), 0.0);
  EXPECT_LT(incircle(0, 0, 1, 0, 1, 1, 3, 3), 0.0);
  EXPECT_EQ(incircle(0, 0, 1, 0, 1, 1, 0, 1), 0.0);
  EXPECT_EQ(incircle(0, 0, 2, 0, 0, 2, 2, 2), 0.0);
  // Clockwise a, b, c: the sign flips.
  EXPECT_LT(incircle(0, 0, 1, 1, 1, 0, 0.5, 0.5), 0.0);
  EXPECT_GT(incircle(0, 0, 1, 1, 1, 0, 3, 3), 0.0);
  // d equal to a vertex: on the circle.
  EXPECT_EQ(incircle(0.1, 0.2, 0.7, 0.3, 0.4, 0.9, 0.7, 0.3), 0.0);
  EXPECT_EQ(incircle(0.1, 0.2, 0.7, 0.3, 0.4, 0.9, 0.1, 0.2), 0.0);
  // A Pythagorean circle (radius 5) moved and scaled by powers of two: exactly cocircular.
  for (int e = -200; e <= 200; e += 25) {
    const double s = std::ldexp(1.0, e);
    EXPECT_EQ(incircle((7 + 3) * s, (11 + 4) * s, (7 - 4) * s, (11 + 3) * s, (7 - 5) * s, 11 * s,
                       (7 + 4) * s, (11 - 3) * s),
              0.0)
        << e;
    EXPECT_GT(incircle((7 + 3) * s, (11 + 4) * s, (7 - 4) * s, (11 + 3) * s, (7 - 5) * s, 11 * s,
                       (7 + 4) * s, (11 - 2) * s),
              0.0)
        << e;
  }
  // Decimal points of the circle x^2 + y^2 = 1: after rounding, whatever the oracle says.
  EXPECT_EQ(sign_of(incircle(0.6, 0.8, -0.8, 0.6, -0.6, -0.8, 0.8, -0.6)),
            exact_incircle_sign(0.6, 0.8, -0.8, 0.6, -0.6, -0.8, 0.8, -0.6));
  // Collinear a, b, c: the "circle" is the line (d to the left of a->b->c counts as outside).
  EXPECT_EQ(incircle(0, 0, 1, 0, 2, 0, 5, 0), 0.0);
  EXPECT_EQ(sign_of(incircle(0, 0, 1, 0, 2, 0, 1, 1)), exact_incircle_sign(0, 0, 1, 0, 2, 0, 1, 1));
  EXPECT_EQ(sign_of(incircle(0, 0, 1, 0, 2, 0, 1, -1)),
            exact_incircle_sign(0, 0, 1, 0, 2, 0, 1, -1));
}

TEST(Predicates, IncircleRandomMatchesOracle) {
  int64_t total = 0;
  for (Range r : kAllRanges) {
    Tally t(std::string("incircle random ") + range_name(r));
    Rng rng(8000 + static_cast<uint64_t>(r));
    for (int i = 0; i < 20000; ++i) {
      Circle4 q;
      for (Point2& p : q.p) {
        p.x = random_coordinate(rng, r);
        p.y = random_coordinate(rng, r);
      }
      check_incircle(t, q);
    }
    t.print();
    EXPECT_EQ(t.wrong, 0) << t.name;
    total += t.cases;
  }
  EXPECT_GE(total, 120000);
}

TEST(Predicates, IncircleNearCocircularMatchesOracle) {
  // Rounded points of a circle, then a few ulps of perturbation.
  Tally perturbed("incircle on a circle +- 3 ulps");
  Rng rng(8101);
  for (int i = 0; i < 40000; ++i) {
    Circle4 q = near_circle(rng, i);
    for (Point2& p : q.p) {
      if (rng.coin()) p.x = ulps(p.x, rng.small(-3, 3));
      if (rng.coin()) p.y = ulps(p.y, rng.small(-3, 3));
    }
    check_incircle(perturbed, q);
  }
  perturbed.print();
  EXPECT_EQ(perturbed.wrong, 0);
  EXPECT_GT(perturbed.naive_wrong, 0) << "the inputs must be hard for the naive formula";

  // d sweeps a 64 x 64 nextafter grid around a rounded point of the circle through a, b, c.
  Tally grid("incircle nextafter grids 64x64");
  for (int config = 0; config < 12; ++config) {
    Circle4 q = near_circle(rng, config);
    const std::vector<double> xs = ulp_row(q.p[3].x);
    const std::vector<double> ys = ulp_row(q.p[3].y);
    for (double x : xs) {
      for (double y : ys) {
        q.p[3] = {x, y};
        check_incircle(grid, q);
      }
    }
  }
  grid.print();
  EXPECT_EQ(grid.wrong, 0);
  EXPECT_GT(grid.naive_wrong, 0);

  // Clusters: four points within a few ulps of 123.456 (differences are not exact).
  Tally cluster("incircle ulp clusters at 123.456");
  for (int i = 0; i < 20000; ++i) {
    Circle4 q;
    for (Point2& p : q.p) {
      p.x = ulps(123.456, rng.small(-40, 40));
      p.y = ulps(-654.321, rng.small(-40, 40));
    }
    check_incircle(cluster, q);
  }
  cluster.print();
  EXPECT_EQ(cluster.wrong, 0);
  EXPECT_GT(cluster.zeros, 0);
}

TEST(Predicates, IncircleExactlyCocircularIsZero) {
  Rng rng(8201);
  Tally rect("incircle rectangle corners (random doubles)");
  Tally pyth("incircle Pythagorean circles (integers scaled)");
  // The corners of any axis-aligned rectangle are cocircular, whatever the coordinates: the
  // differences are not exact in general, so this reaches the exact stage.
  for (int i = 0; i < 20000; ++i) {
    const Range r = kAllRanges[i % 6];
    const double x0 = random_coordinate(rng, r), x1 = random_coordinate(rng, r);
    const double y0 = random_coordinate(rng, r), y1 = random_coordinate(rng, r);
    Point2 corners[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    Circle4 q;
    for (int k = 0; k < 4; ++k) q.p[k] = corners[(k + i) % 4];
    if (i % 3 == 0) std::swap(q.p[1], q.p[2]);
    const int expected = check_incircle(rect, q);
    ASSERT_EQ(expected, 0);
    ASSERT_EQ(
        incircle(q.p[0].x, q.p[0].y, q.p[1].x, q.p[1].y, q.p[2].x, q.p[2].y, q.p[3].x, q.p[3].y),
        0.0);
  }
  // Integer points of x^2 + y^2 = 25 (and 65^2), moved to an integer centre and scaled.
  const int p5[12][2] = {{5, 0},  {4, 3},   {3, 4},   {0, 5},  {-3, 4}, {-4, 3},
                         {-5, 0}, {-4, -3}, {-3, -4}, {0, -5}, {3, -4}, {4, -3}};
  const int p65[8][2] = {{65, 0},  {63, 16}, {60, 25}, {56, 33},
                         {52, 39}, {39, 52}, {33, 56}, {16, 63}};
  for (int i = 0; i < 20000; ++i) {
    const double scale = std::ldexp(1.0, rng.small(-150, 150));
    const double cx = static_cast<double>(rng.small(-1000, 1000));
    const double cy = static_cast<double>(rng.small(-1000, 1000));
    Circle4 q;
    for (Point2& p : q.p) {
      double x, y;
      if (i % 2 == 0) {
        const int k = rng.small(0, 11);
        x = p5[k][0];
        y = p5[k][1];
      } else {
        const int k = rng.small(0, 7);
        x = rng.coin() ? p65[k][0] : -p65[k][0];
        y = rng.coin() ? p65[k][1] : -p65[k][1];
      }
      p = {(cx + x) * scale, (cy + y) * scale};
    }
    ASSERT_EQ(check_incircle(pyth, q), 0);
  }
  rect.print();
  pyth.print();
  EXPECT_EQ(rect.wrong, 0);
  EXPECT_EQ(pyth.wrong, 0);
  EXPECT_GT(rect.naive_wrong, 0);
}

TEST(Predicates, IncircleNearRangeLimitsMatchOracle) {
  // The documented range is 2^-216 <= |x| <= 2^240 for nonzero coordinates.
  Tally t("incircle grids scaled by 2^228 and 2^-216");
  Rng rng(8301);
  for (int config = 0; config < 8; ++config) {
    Circle4 q;
    bool ok = false;
    while (!ok) {
      q = near_circle(rng, 1);
      ok = true;
      for (const Point2& p : q.p) {
        ok = ok && std::fabs(p.x) >= 1.5 && std::fabs(p.x) < 1024 && std::fabs(p.y) >= 1.5 &&
             std::fabs(p.y) < 1024;
      }
    }
    const double scale = std::ldexp(1.0, config % 2 == 0 ? 228 : -216);
    for (Point2& p : q.p) p = {p.x * scale, p.y * scale};
    const std::vector<double> xs = ulp_row(q.p[config % 4].x);
    const std::vector<double> ys = ulp_row(q.p[config % 4].y);
    for (size_t i = 0; i < 64; i += 2) {
      for (size_t j = 0; j < 64; j += 2) {
        q.p[config % 4] = {xs[i], ys[j]};
        check_incircle(t, q);
      }
    }
  }
  t.print();
  EXPECT_EQ(t.wrong, 0);

  // Clusters a few ulps apart at the low end: the products of four differences are subnormal.
  Tally cluster("incircle ulp clusters at 2^-216");
  for (int i = 0; i < 20000; ++i) {
    const double scale = 0x1p-216;
    const double bx = rng.signed_uniform(1.5, 2.0) * scale;
    const double by = rng.signed_uniform(1.5, 2.0) * scale;
    Circle4 q;
    for (Point2& p : q.p) p = {ulps(bx, rng.small(-16, 16)), ulps(by, rng.small(-16, 16))};
    check_incircle(cluster, q);
  }
  cluster.print();
  EXPECT_EQ(cluster.wrong, 0);
  EXPECT_GT(cluster.zeros, 0);
}

TEST(Predicates, IncirclePermutationsChangeSignExactly) {
  Rng rng(8401);
  Tally t("incircle permutation symmetry (base queries)");
  for (int i = 0; i < 20000; ++i) {
    Circle4 q = near_circle(rng, i);
    for (Point2& p : q.p) {
      if (rng.coin()) p.x = ulps(p.x, rng.small(-2, 2));
    }
    const int s = check_incircle(t, q);
    // The lifted determinant is alternating: every transposition negates.
    auto sign_of_order = [&q](int i0, int i1, int i2, int i3) {
      return sign_of(incircle(q.p[i0].x, q.p[i0].y, q.p[i1].x, q.p[i1].y, q.p[i2].x, q.p[i2].y,
                              q.p[i3].x, q.p[i3].y));
    };
    ASSERT_EQ(sign_of_order(1, 0, 2, 3), -s);
    ASSERT_EQ(sign_of_order(0, 2, 1, 3), -s);
    ASSERT_EQ(sign_of_order(3, 1, 2, 0), -s);
    ASSERT_EQ(sign_of_order(0, 1, 3, 2), -s);
    ASSERT_EQ(sign_of_order(1, 2, 0, 3), s);
    ASSERT_EQ(sign_of_order(3, 2, 1, 0), s);
    ASSERT_EQ(sign_of_order(1, 0, 3, 2), s);
  }
  t.print();
  EXPECT_EQ(t.wrong, 0);
}

// As ResultBitsArePinned, for incircle.
TEST(Predicates, IncircleResultBitsArePinned) {
  uint64_t h = 0;
  Rng rng(8501);
  for (int config = 0; config < 6; ++config) {
    Circle4 q = near_circle(rng, config);
    const std::vector<double> xs = ulp_row(q.p[3].x);
    const std::vector<double> ys = ulp_row(q.p[3].y);
    for (size_t i = 0; i < 64; i += 3) {
      for (size_t j = 0; j < 64; j += 3) {
        q.p[3] = {xs[i], ys[j]};
        h = fold(h, incircle(q.p[0].x, q.p[0].y, q.p[1].x, q.p[1].y, q.p[2].x, q.p[2].y, q.p[3].x,
                             q.p[3].y));
      }
    }
  }
  for (int i = 0; i < 2000; ++i) {
    const Range r = kAllRanges[i % 6];
    double c[8];
    for (double& v : c) v = random_coordinate(rng, r);
    h = fold(h, incircle(c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]));
  }
  std::printf("[   info   ] result hash: incircle 0x%016llx\n", static_cast<unsigned long long>(h));
  EXPECT_EQ(h, 0x30dd3b9f3430ac1aull);
}

}  // namespace

namespace {

// normal_dot(a, b, c, d) = ((b - a) x (c - a)) . d = -orient3d(a, b, c, a + d): with a and d
// dyadic (so a + d is an exact double) the oracle's orient3d sign decides it. c starts in
// the plane through a, b along d (normal_dot exactly 0), then moves by a few ulps.
TEST(Predicates, NormalDotNearDegenerateMatchesOracle) {
  Rng rng(4010);
  int wrong = 0, zero = 0, naive_wrong = 0;
  for (int n = 0; n < 60000; ++n) {
    const Vec3 a{rng.dyadic(-(1 << 20), 1 << 20, -12, -8), rng.dyadic(-(1 << 20), 1 << 20, -12, -8),
                 rng.dyadic(-(1 << 20), 1 << 20, -12, -8)};
    const Vec3 d{rng.dyadic(-(1 << 10), 1 << 10, -10, -10),
                 rng.dyadic(-(1 << 10), 1 << 10, -10, -10),
                 rng.dyadic(-(1 << 10), 1 << 10, -10, -10)};
    const Vec3 b{rng.float32(-100, 100), rng.float32(-100, 100), rng.float32(-100, 100)};
    const double s = rng.dyadic(-64, 64, -6, -6), t = rng.dyadic(-64, 64, -6, -6);
    Vec3 c = a + (b - a) * s + d * t;  // rounded: near the plane, often on it
    if (n % 2 == 1) {
      const int axis = rng.small(0, 2);
      c[axis] = ulps(c[axis], rng.small(-3, 3));
    }
    const Vec3 p = a + d;
    const int expected = -exact_orient3d_sign(a, b, c, p);
    const int got = sign_of(splintcore::normal_dot(a, b, c, d));
    wrong += got != expected ? 1 : 0;
    zero += expected == 0 ? 1 : 0;
    const Vec3 u = b - a, v = c - a;
    const double naive = (u.y * v.z - u.z * v.y) * d.x + (u.z * v.x - u.x * v.z) * d.y +
                         (u.x * v.y - u.y * v.x) * d.z;
    naive_wrong += sign_of(naive) != expected ? 1 : 0;
  }
  std::printf(
      "[ figures  ] normal_dot near its plane: 60000 cases, %d exactly 0, %d wrong, "
      "naive double %d wrong\n",
      zero, wrong, naive_wrong);
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(zero, 100);
  EXPECT_GT(naive_wrong, 0);
}

}  // namespace

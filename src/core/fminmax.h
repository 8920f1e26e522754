// fmin, fmax and a clamp to [0, 1] with one meaning on every target (private to the library).
// std::fmin and std::fmax may give either zero when both arguments are zeros: glibc on x86-64
// gives the second, AArch64's fminnm/fmaxnm order them by sign, a libm in C the first. A zero's
// sign can reach output bytes, so these say which: the first argument when it is the smaller
// (min_of) or the larger (max_of), or when the second is NaN; else the second. Those are
// glibc's x86-64 results bit for bit, and C++'s own comparisons everywhere else. They also stay
// inline (GCC calls libm's for their NaN rule): one or two instructions, not a call.
#ifndef SPLINTCORE_SRC_CORE_FMINMAX_H
#define SPLINTCORE_SRC_CORE_FMINMAX_H

#include <cmath>

namespace splintcore {

inline double min_of(double a, double b) { return (a < b || std::isnan(b)) ? a : b; }
inline double max_of(double a, double b) { return (a > b || std::isnan(b)) ? a : b; }

// The least and the greatest of three, by the same rule (a triangle's box along one axis).
inline double min3_of(double a, double b, double c) { return min_of(a, min_of(b, c)); }
inline double max3_of(double a, double b, double c) { return max_of(a, max_of(b, c)); }

// t limited to [0, 1] (a parameter along a segment); NaN stays NaN.
inline double clamp01(double t) { return t < 0 ? 0 : (t > 1 ? 1 : t); }

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CORE_FMINMAX_H

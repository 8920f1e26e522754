// Monotonic time for tools and benchmarks; never reaches output bytes.
#include <chrono>

#include "splintcore/platform.h"

namespace splintcore {

double monotonic_seconds() {
  using Clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
}

}  // namespace splintcore

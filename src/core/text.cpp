// Small text checks shared by the case file, the STL writer and the tools.
#include "splintcore/core.h"

namespace splintcore {

bool parse_byte_size(const char* text, uint64_t* out) {
  if (text == nullptr) return false;
  size_t n = std::strlen(text);
  if (n == 0) return false;
  uint64_t scale = 1;
  const char last = text[n - 1];
  if (last == 'K' || last == 'k') scale = uint64_t{1} << 10;
  if (last == 'M' || last == 'm') scale = uint64_t{1} << 20;
  if (last == 'G' || last == 'g') scale = uint64_t{1} << 30;
  if (scale != 1) --n;
  if (n == 0 || n > 19) return false;
  uint64_t value = 0;
  for (size_t i = 0; i < n; ++i) {
    if (text[i] < '0' || text[i] > '9') return false;
    if (!checked_mul(value, 10, &value) ||
        !checked_add(value, static_cast<uint64_t>(text[i] - '0'), &value)) {
      return false;
    }
  }
  return checked_mul(value, scale, out);
}

bool is_plain_name(const char* text, size_t max_length) {
  if (text == nullptr) return false;
  const size_t n = std::strlen(text);
  if (n == 0 || n > max_length) return false;
  for (size_t i = 0; i < n; ++i) {
    const char c = text[i];
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

#ifndef SPLINTCORE_VERSION
#error "SPLINTCORE_VERSION is set by CMakeLists.txt"
#endif
const char* library_version() { return SPLINTCORE_VERSION; }

}  // namespace splintcore

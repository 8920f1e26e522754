#include "options.h"

#include <charconv>
#include <cstring>

#include "../common/cli.h"

namespace splintcore {
namespace tool {

namespace {

OptionSpec make(const char* name, const char* value_name, OptionKind kind, void* target,
                const char* help, const char* error) {
  OptionSpec s;
  s.name = name;
  s.value_name = value_name;
  s.kind = kind;
  s.target = target;
  s.help = help;
  s.error = error;
  return s;
}

bool takes_value(OptionKind kind) {
  return kind != OptionKind::kFlag && kind != OptionKind::kClear && kind != OptionKind::kOneOf;
}

// A whole value read as a double (nothing left over, in range).
bool parse_real(const char* text, double* out) {
  const char* end = text + std::strlen(text);
  const auto r = std::from_chars(text, end, *out);
  return r.ec == std::errc() && r.ptr == end;
}

// The value's index in a '|'-separated list of choices, or -1.
int find_choice(const char* choices, const char* value) {
  const size_t n = std::strlen(value);
  int index = 0;
  for (const char* p = choices;; ++index) {
    const char* bar = std::strchr(p, '|');
    const size_t length = bar != nullptr ? static_cast<size_t>(bar - p) : std::strlen(p);
    if (length == n && std::strncmp(p, value, n) == 0) return index;
    if (bar == nullptr) return -1;
    p = bar + 1;
  }
}

// The options that take no value: true when set, else the usage error.
bool apply_flag(const OptionSpec& s) {
  if (s.kind == OptionKind::kOneOf) {
    int* target = static_cast<int*>(s.target);
    const int number = static_cast<int>(s.min);
    if (*target >= 0 && *target != number) return false;
    *target = number;
  } else {
    *static_cast<bool*>(s.target) = s.kind == OptionKind::kFlag;
  }
  return true;
}

// Reads `value` into the option's target. Returns nullptr, or the usage error.
const char* apply_value(const OptionSpec& s, const char* value) {
  uint64_t n = 0;
  double x = 0;
  switch (s.kind) {
    case OptionKind::kText: *static_cast<const char**>(s.target) = value; return nullptr;
    case OptionKind::kChoice: {
      const int index = find_choice(s.value_name, value);
      if (index < 0) return s.error;
      *static_cast<int*>(s.target) = index;
      return nullptr;
    }
    case OptionKind::kCount:
      if (!cli::parse_unsigned(value, &n) || n < s.min || n > s.max) return s.error;
      *static_cast<uint64_t*>(s.target) = n;
      return nullptr;
    case OptionKind::kSize:
    case OptionKind::kMemoryCap:
      if (!cli::parse_size(value, &n) || n == 0) return s.error;
      if (s.kind == OptionKind::kMemoryCap && n > (uint64_t{1} << 40)) {
        return "--memory-cap is over 1T";
      }
      *static_cast<uint64_t*>(s.target) = n;
      return nullptr;
    case OptionKind::kInt16: {
      int32_t v = 0;
      const char* end = value + std::strlen(value);
      const auto r = std::from_chars(value, end, v);
      if (r.ec != std::errc() || r.ptr != end || v < -32768 || v > 32767) return s.error;
      *static_cast<int32_t*>(s.target) = v;
      return nullptr;
    }
    case OptionKind::kReal:
    case OptionKind::kNonNegative:
    case OptionKind::kPositive:
      if (!parse_real(value, &x)) return s.error;
      if (s.kind != OptionKind::kReal && (!is_finite(x) || x < 0)) return s.error;
      if (s.kind == OptionKind::kPositive && !(x > 0)) return s.error;
      *static_cast<double*>(s.target) = x;
      return nullptr;
    case OptionKind::kPoint:
    case OptionKind::kDirection: {
      Vec3 p;
      if (!parse_point(value, &p)) return s.error;
      if (s.kind == OptionKind::kDirection && length(p) == 0) return s.error;
      *static_cast<Vec3*>(s.target) = p;
      return nullptr;
    }
    case OptionKind::kPointList: {
      Vec3 p;
      if (!parse_point(value, &p)) return s.error;
      static_cast<std::vector<Vec3>*>(s.target)->push_back(p);
      return nullptr;
    }
    case OptionKind::kCustom: return s.parse(value, s.target) ? nullptr : s.error;
    default: return s.error;
  }
}

const OptionSpec* find_option(const std::vector<OptionSpec>& specs, const char* arg) {
  for (const OptionSpec& s : specs) {
    if (std::strcmp(arg, s.name) == 0) return &s;
    if (s.alias != nullptr && std::strcmp(arg, s.alias) == 0) return &s;
  }
  return nullptr;
}

}  // namespace

OptionSpec OptionSpec::marks(bool* flag) const {
  OptionSpec s = *this;
  s.given = flag;
  return s;
}

OptionSpec OptionSpec::or_as(const char* other) const {
  OptionSpec s = *this;
  s.alias = other;
  return s;
}

OptionSpec flag(const char* name, bool* target, const char* help) {
  return make(name, nullptr, OptionKind::kFlag, target, help, "");
}
OptionSpec clear_flag(const char* name, bool* target, const char* help) {
  return make(name, nullptr, OptionKind::kClear, target, help, "");
}
OptionSpec one_of(const char* name, int* target, int number, const char* help, const char* error) {
  OptionSpec s = make(name, nullptr, OptionKind::kOneOf, target, help, error);
  s.min = static_cast<uint64_t>(number);
  return s;
}
OptionSpec text(const char* name, const char* value_name, const char** target, const char* help,
                const char* error) {
  return make(name, value_name, OptionKind::kText, target, help, error);
}
OptionSpec choice(const char* name, const char* choices, int* target, const char* help,
                  const char* error) {
  return make(name, choices, OptionKind::kChoice, target, help, error);
}
OptionSpec count(const char* name, const char* value_name, uint64_t* target, uint64_t min,
                 uint64_t max, const char* help, const char* error) {
  OptionSpec s = make(name, value_name, OptionKind::kCount, target, help, error);
  s.min = min;
  s.max = max;
  return s;
}
OptionSpec size(const char* name, const char* value_name, uint64_t* target, const char* help,
                const char* error) {
  return make(name, value_name, OptionKind::kSize, target, help, error);
}
OptionSpec memory_cap(const char* name, uint64_t* target, const char* help, const char* error) {
  return make(name, "SIZE", OptionKind::kMemoryCap, target, help, error);
}
OptionSpec int16(const char* name, const char* value_name, int32_t* target, const char* help,
                 const char* error) {
  return make(name, value_name, OptionKind::kInt16, target, help, error);
}
OptionSpec real(const char* name, const char* value_name, double* target, const char* help,
                const char* error) {
  return make(name, value_name, OptionKind::kReal, target, help, error);
}
OptionSpec non_negative(const char* name, const char* value_name, double* target, const char* help,
                        const char* error) {
  return make(name, value_name, OptionKind::kNonNegative, target, help, error);
}
OptionSpec positive(const char* name, const char* value_name, double* target, const char* help,
                    const char* error) {
  return make(name, value_name, OptionKind::kPositive, target, help, error);
}
OptionSpec point(const char* name, const char* value_name, Vec3* target, const char* help,
                 const char* error) {
  return make(name, value_name, OptionKind::kPoint, target, help, error);
}
OptionSpec point_list(const char* name, const char* value_name, std::vector<Vec3>* target,
                      const char* help, const char* error) {
  return make(name, value_name, OptionKind::kPointList, target, help, error);
}
OptionSpec direction(const char* name, const char* value_name, Vec3* target, const char* help,
                     const char* error) {
  return make(name, value_name, OptionKind::kDirection, target, help, error);
}

bool parse_options(const std::vector<OptionSpec>& specs, int argc, char** argv,
                   std::vector<const char*>* positional, std::string* error) {
  for (int i = 0; i < argc; ++i) {
    const char* arg = argv[i];
    const OptionSpec* s = find_option(specs, arg);
    if (s == nullptr && arg[0] == '-' && arg[1] != '\0') {
      *error = std::string("unknown option '") + arg + "'";
      return false;
    }
    if (s == nullptr) {
      positional->push_back(arg);
      continue;
    }
    const char* problem = nullptr;
    if (!takes_value(s->kind)) {
      if (!apply_flag(*s)) problem = s->error;
    } else if (i + 1 >= argc) {
      problem = s->error;
    } else {
      problem = apply_value(*s, argv[++i]);
    }
    if (problem != nullptr) {
      *error = problem;
      return false;
    }
    if (s->given != nullptr) *s->given = true;
  }
  return true;
}

void print_options(std::FILE* out, const std::vector<OptionSpec>& specs) {
  for (const OptionSpec& s : specs) {
    std::string left = s.name;
    if (s.value_name != nullptr) left += std::string(" ") + s.value_name;
    if (left.size() <= 17) {
      std::fprintf(out, "  %-17s %s\n", left.c_str(), s.help);
    } else {
      std::fprintf(out, "  %s\n  %-17s %s\n", left.c_str(), "", s.help);
    }
  }
}

bool parse_point(const char* text, Vec3* out) {
  const char* p = text;
  for (int a = 0; a < 3; ++a) {
    const char* end = p;
    while (*end != '\0' && *end != ',') ++end;
    double value = 0;
    auto r = std::from_chars(p, end, value);
    if (r.ec != std::errc() || r.ptr != end || !is_finite(value)) return false;
    (*out)[a] = value;
    if (a < 2) {
      if (*end != ',') return false;
      p = end + 1;
    } else if (*end != '\0') {
      return false;
    }
  }
  return true;
}

}  // namespace tool
}  // namespace splintcore

// The one option parser of the splintcore program (issue 27). Every command describes its options
// in a table: per option its name, the kind of value it takes, the field it writes, one line of
// help and the usage error for a missing or malformed value. The parser reads the command line
// against that table, and the command's --help lists it, so what a command accepts and what its
// help says cannot drift apart. The model is git's parse-options (an array of `struct option`
// bound to the caller's variables, usage printed from the same array).
#ifndef SPLINTCORE_TOOLS_SPLINTCORE_OPTIONS_H
#define SPLINTCORE_TOOLS_SPLINTCORE_OPTIONS_H

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "splintcore/geometry.h"

namespace splintcore {
namespace tool {

// What an option's value is, and so what its target field must be.
enum class OptionKind {
  kFlag,         // bool, set true; takes no value
  kClear,        // bool, set false (the --no-... options); takes no value
  kOneOf,        // int, set to the option's number (`min`); takes no value. Several kOneOf
                 // options share a target: giving two different ones is the usage error
  kText,         // const char*: the value as given
  kChoice,       // int: the value's index in value_name, a '|'-separated list ("6|26")
  kCount,        // uint64_t: a decimal count from `min` to `max`
  kSize,         // uint64_t: a size such as 64M, 2G or 1048576 (cli::parse_size), not 0
  kMemoryCap,    // uint64_t: a size as kSize, at most 1T
  kInt16,        // int32_t: an integer from -32768 to 32767 (a CT value, HU)
  kReal,         // double: any number std::from_chars reads (whole value)
  kNonNegative,  // double: a finite number >= 0
  kPositive,     // double: a finite number > 0
  kPoint,        // Vec3: X,Y,Z, three finite numbers
  kPointList,    // std::vector<Vec3>: each X,Y,Z given is appended (the option repeats)
  kDirection,    // Vec3: X,Y,Z, finite and not all 0
  kCustom,       // whatever `parse` writes
};

// One option of one command. Build them with the functions below, which check the target's
// type against the kind.
struct OptionSpec {
  const char* name = nullptr;        // "--voxel", or "-o"
  const char* value_name = nullptr;  // shown in --help ("H"); nullptr for the kinds without one
  OptionKind kind = OptionKind::kFlag;
  void* target = nullptr;
  const char* help = "";        // one line for --help
  const char* error = "";       // the usage error for a missing or malformed value
  const char* alias = nullptr;  // another spelling accepted (-h, --output), not shown in --help
  bool* given = nullptr;        // if set, becomes true when the option appears
  uint64_t min = 0;             // kCount's range; kOneOf's number in `min`
  uint64_t max = UINT64_MAX;
  bool (*parse)(const char* value, void* target) = nullptr;  // kCustom

  // The same option, also marking `*flag` when it appears (a field with no "unset" value).
  OptionSpec marks(bool* flag) const;
  // The same option, also accepted as `other`.
  OptionSpec or_as(const char* other) const;
};

OptionSpec flag(const char* name, bool* target, const char* help);
OptionSpec clear_flag(const char* name, bool* target, const char* help);
OptionSpec one_of(const char* name, int* target, int number, const char* help, const char* error);
OptionSpec text(const char* name, const char* value_name, const char** target, const char* help,
                const char* error);
OptionSpec choice(const char* name, const char* choices, int* target, const char* help,
                  const char* error);
OptionSpec count(const char* name, const char* value_name, uint64_t* target, uint64_t min,
                 uint64_t max, const char* help, const char* error);
OptionSpec size(const char* name, const char* value_name, uint64_t* target, const char* help,
                const char* error);
OptionSpec memory_cap(const char* name, uint64_t* target, const char* help, const char* error);
OptionSpec int16(const char* name, const char* value_name, int32_t* target, const char* help,
                 const char* error);
OptionSpec real(const char* name, const char* value_name, double* target, const char* help,
                const char* error);
OptionSpec non_negative(const char* name, const char* value_name, double* target, const char* help,
                        const char* error);
OptionSpec positive(const char* name, const char* value_name, double* target, const char* help,
                    const char* error);
OptionSpec point(const char* name, const char* value_name, Vec3* target, const char* help,
                 const char* error);
OptionSpec point_list(const char* name, const char* value_name, std::vector<Vec3>* target,
                      const char* help, const char* error);
OptionSpec direction(const char* name, const char* value_name, Vec3* target, const char* help,
                     const char* error);

// An option whose value `Parse` reads into a T (false: the usage error).
template <typename T, bool (*Parse)(const char*, T*)>
OptionSpec custom(const char* name, const char* value_name, T* target, const char* help,
                  const char* error) {
  OptionSpec s;
  s.name = name;
  s.value_name = value_name;
  s.kind = OptionKind::kCustom;
  s.target = target;
  s.help = help;
  s.error = error;
  s.parse = [](const char* value, void* t) { return Parse(value, static_cast<T*>(t)); };
  return s;
}

// Reads argv (the arguments after the command's name) against `specs`, left to right: an
// argument naming an option sets its target, taking the next argument as its value when its
// kind has one (whatever that argument looks like); any other argument starting with '-' (but
// "-" alone) is an unknown option; the rest go to `positional` in order. Returns false at the
// first problem with the usage error in `*error`: "unknown option '--frob'", or the option's
// own error for a missing or malformed value.
bool parse_options(const std::vector<OptionSpec>& specs, int argc, char** argv,
                   std::vector<const char*>* positional, std::string* error);

// The --help lines of `specs`, in order: "  NAME VALUE" then the help, in a column from the
// 21st character (on the next line when the name and value are longer).
void print_options(std::FILE* out, const std::vector<OptionSpec>& specs);

// "X,Y,Z" -> a point; false when malformed or not finite.
bool parse_point(const char* text, Vec3* out);

}  // namespace tool
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_SPLINTCORE_OPTIONS_H

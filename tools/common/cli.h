// Helpers shared by the command-line programs: sizes, JSON output, status printing.
#ifndef SPLINTCORE_TOOLS_CLI_H
#define SPLINTCORE_TOOLS_CLI_H

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "splintcore/core.h"
#include "splintcore/geometry.h"

namespace splintcore {
namespace cli {

// Exit codes of every subcommand.
constexpr int kExitOk = 0;
constexpr int kExitRejected = 1;  // input rejected, check failed, or resources exhausted
constexpr int kExitUsage = 2;

// "64M", "1G", "512K", "1048576" -> bytes (binary multiples). False when malformed.
bool parse_size(const char* text, uint64_t* out);
bool parse_unsigned(const char* text, uint64_t* out);

// A flat JSON object written in insertion order; numbers in shortest round-trip form.
class JsonObject {
 public:
  void add(const char* key, const char* value);
  void add(const char* key, const std::string& value) { add(key, value.c_str()); }
  void add(const char* key, bool value);
  void add(const char* key, uint64_t value);
  void add(const char* key, int64_t value);
  void add(const char* key, int value) { add(key, static_cast<int64_t>(value)); }
  void add(const char* key, unsigned value) { add(key, static_cast<uint64_t>(value)); }
  void add(const char* key, double value);
  void add(const char* key, const Vec3& value);
  void add_raw(const char* key, const std::string& json);
  void add_status(const Status& status);  // "status", "message" and the location fields
  std::string str() const { return "{" + body_ + "}"; }

 private:
  void key(const char* k);
  std::string body_;
};

std::string json_escape(const char* text);
std::string json_number(double value);

// Reads a whole file into `out`; false when it cannot be opened or read.
bool read_whole_file(const std::string& path, std::vector<uint8_t>* out);

// Prints "splintcore: <formatted status>" to stderr.
void print_error(const Status& status);

}  // namespace cli
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_CLI_H

// splintcore json: a strict JSON (RFC 8259) parser into the arena, for the case file.
// Floor 4 (io). Bounded size and nesting depth; errors carry line and column; duplicate keys
// are rejected; numbers are parsed exactly (correctly rounded, locale-free std::from_chars).
#ifndef SPLINTCORE_JSON_H
#define SPLINTCORE_JSON_H

#include "splintcore/core.h"

namespace splintcore {

enum class JsonType : uint8_t { kNull, kBool, kNumber, kString, kArray, kObject };

const char* json_type_name(JsonType type);

constexpr uint32_t kJsonNone = ~uint32_t{0};

// One value. Children of arrays and objects are linked: first_child, then next_sibling.
struct JsonValue {
  JsonType type = JsonType::kNull;
  bool boolean = false;
  double number = 0.0;
  const char* string = nullptr;  // kString: UTF-8, NUL-terminated, `length` bytes
  uint32_t length = 0;
  const char* key = nullptr;  // when this value is an object member: its key (NUL-terminated)
  uint32_t key_length = 0;
  uint32_t first_child = kJsonNone;
  uint32_t next_sibling = kJsonNone;
  uint32_t child_count = 0;
  uint32_t line = 0;  // where the value starts (1-based)
  uint32_t column = 0;
};

struct JsonLimits {
  size_t max_bytes = 4 << 20;  // larger documents are kLimitExceeded
  uint32_t max_depth = 32;     // nesting of arrays and objects
  uint32_t max_values = 1 << 20;
};

struct JsonDocument {
  Span<const JsonValue> values;  // values[0] is the root
  const char* name = nullptr;    // the document's name for messages (a file name)

  const JsonValue& root() const { return values[0]; }
  const JsonValue& at(uint32_t index) const { return values[index]; }
  // Member of an object by key, or nullptr.
  const JsonValue* member(const JsonValue& object, const char* key) const;
  // Index of a value in values (for walking children).
  uint32_t index_of(const JsonValue& v) const {
    return static_cast<uint32_t>(&v - values.data());
  }
};

// Parses `text` (not necessarily NUL-terminated). The values and strings live in the arena
// (length + 1 bytes of strings plus sizeof(JsonValue) per value, with growth); on failure the
// arena is rewound to where it was.
// Errors: kParseError (with line and column), kLimitExceeded, kArenaExhausted.
Status parse_json(const Context& ctx, const char* text, size_t length, const JsonLimits& limits,
                  const char* name, JsonDocument* out);

// An error located at a value: "NAME:LINE:COL: message".
Status json_error(const JsonDocument& doc, const JsonValue& at, StatusCode code,
                  const char* message);

}  // namespace splintcore

#endif  // SPLINTCORE_JSON_H

// splintcore json: a strict JSON (RFC 8259) parser into the arena, for the case file, and a
// streaming writer into a byte sink, for the audit report. Parser: bounded size and nesting depth;
// errors carry line and column; duplicate keys are rejected; numbers are parsed exactly (correctly
// rounded, locale-free std::from_chars). Writer: compact, numbers as the shortest text that reads
// back to the same double (std::to_chars), no heap.
#ifndef SPLINTCORE_JSON_H
#define SPLINTCORE_JSON_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/io.h"

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
  uint32_t index_of(const JsonValue& v) const { return static_cast<uint32_t>(&v - values.data()); }
};

// Parses `text` (not necessarily NUL-terminated). The values and strings live in the arena
// (length + 1 bytes of strings plus sizeof(JsonValue) per value, with growth): at most
// parse_json_bound(length, limits). On failure the arena is rewound to where it was.
// Errors: kParseError (with line and column), kLimitExceeded, kArenaExhausted.
uint64_t parse_json_bound(uint64_t length, const JsonLimits& limits);
Status parse_json(const Context& ctx, const char* text, size_t length, const JsonLimits& limits,
                  const char* name, JsonDocument* out);

// An error located at a value: "NAME:LINE:COL: message".
Status json_error(const JsonDocument& doc, const JsonValue& at, StatusCode code,
                  const char* message);

// ---------------------------------------------------------------------------------------------
// The writer: compact JSON into a ByteSink through a 256-byte buffer of its own (no arena).
// Inside an object every value takes a key; inside an array (and at the top) key is nullptr.
// Strings are escaped as RFC 8259 asks (", \ and control characters; UTF-8 passes through);
// a number that is not finite is written as null. The first failure (the sink refused bytes,
// nesting deeper than 64 or unbalanced, a key where none belongs or none where one does) is
// kept, later calls do nothing, and finish() returns it.
class JsonWriter {
 public:
  explicit JsonWriter(const ByteSink& sink) : sink_(sink) {}
  JsonWriter(const JsonWriter&) = delete;
  JsonWriter& operator=(const JsonWriter&) = delete;

  void begin_object(const char* key = nullptr);
  void end_object();
  void begin_array(const char* key = nullptr);
  void end_array();
  void add(const char* key, const char* value);  // nullptr: null
  void add(const char* key, bool value);
  void add(const char* key, uint64_t value);
  void add(const char* key, int64_t value);
  void add(const char* key, uint32_t value) { add(key, uint64_t{value}); }
  void add(const char* key, int value) { add(key, int64_t{value}); }
  void add(const char* key, double value);
  void add(const char* key, const Vec3& value);  // [x, y, z]
  void add_null(const char* key);

  // Flushes the buffer; ok, or the first failure.
  [[nodiscard]] Status finish();

 private:
  void open(const char* key, char bracket, bool object);
  void close(char bracket, bool object);
  void value_start(const char* key);
  void put(const char* text, size_t length);
  void put_char(char c) { put(&c, 1); }
  void put_string(const char* text);
  void put_number(double value);
  void flush();
  void fail(const char* what);

  static constexpr uint32_t kMaxDepth = 64;
  ByteSink sink_;
  Status status_;
  uint64_t object_bits_ = 0;  // bit d: the container at depth d + 1 is an object
  uint64_t empty_bits_ = 0;   // bit d: it has no element yet
  uint32_t depth_ = 0;
  bool top_written_ = false;
  size_t fill_ = 0;
  char buffer_[256] = {};
};

}  // namespace splintcore

#endif  // SPLINTCORE_JSON_H

// The JSON writer (json.h): RFC 8259 text, compact, streamed through a small buffer.
#include <charconv>
#include <cstring>

#include "splintcore/json.h"

namespace splintcore {

void JsonWriter::fail(const char* what) {
  if (status_.is_ok()) status_ = make_error(StatusCode::kInvalidArgument, "JSON writer: ", what);
}

void JsonWriter::flush() {
  if (fill_ == 0 || !status_.is_ok()) return;
  if (sink_.write == nullptr ||
      !sink_.write(sink_.user, reinterpret_cast<const uint8_t*>(buffer_), fill_)) {
    status_ = make_error(StatusCode::kIoError, "cannot write ",
                         sink_.name != nullptr ? sink_.name : "the JSON output");
  }
  fill_ = 0;
}

void JsonWriter::put(const char* text, size_t length) {
  while (length > 0 && status_.is_ok()) {
    if (fill_ == sizeof(buffer_)) flush();
    size_t n = sizeof(buffer_) - fill_;
    if (n > length) n = length;
    std::memcpy(buffer_ + fill_, text, n);
    fill_ += n;
    text += n;
    length -= n;
  }
}

void JsonWriter::put_string(const char* text) {
  static const char kHex[] = "0123456789abcdef";
  put_char('"');
  for (const char* p = text; *p != '\0'; ++p) {
    const unsigned char c = static_cast<unsigned char>(*p);
    if (c == '"' || c == '\\') {
      const char e[2] = {'\\', static_cast<char>(c)};
      put(e, 2);
    } else if (c < 0x20) {
      const char e[6] = {'\\', 'u', '0', '0', kHex[c >> 4], kHex[c & 15]};
      put(e, 6);
    } else {
      put_char(static_cast<char>(c));
    }
  }
  put_char('"');
}

void JsonWriter::put_number(double value) {
  if (!is_finite(value)) {
    put("null", 4);
    return;
  }
  char digits[32];
  const auto r = std::to_chars(digits, digits + sizeof(digits), value);
  put(digits, static_cast<size_t>(r.ptr - digits));
}

// Writes the separator and the key (in an object) before a value.
void JsonWriter::value_start(const char* key) {
  if (!status_.is_ok()) return;
  if (depth_ == 0) {
    if (top_written_) return fail("a second value at the top level");
    if (key != nullptr) return fail("a key at the top level");
    top_written_ = true;
    return;
  }
  const uint64_t bit = uint64_t{1} << (depth_ - 1);
  const bool in_object = (object_bits_ & bit) != 0;
  if (in_object != (key != nullptr)) {
    return fail(in_object ? "a value without a key in an object" : "a key in an array");
  }
  if ((empty_bits_ & bit) == 0) put_char(',');
  empty_bits_ &= ~bit;
  if (key != nullptr) {
    put_string(key);
    put_char(':');
  }
}

void JsonWriter::open(const char* key, char bracket, bool object) {
  value_start(key);
  if (!status_.is_ok()) return;
  if (depth_ == kMaxDepth) return fail("nesting deeper than 64");
  const uint64_t bit = uint64_t{1} << depth_;
  object_bits_ = object ? (object_bits_ | bit) : (object_bits_ & ~bit);
  empty_bits_ |= bit;
  ++depth_;
  put_char(bracket);
}

void JsonWriter::close(char bracket, bool object) {
  if (!status_.is_ok()) return;
  if (depth_ == 0) return fail("a close without an open");
  const bool is_object = (object_bits_ >> (depth_ - 1) & 1) != 0;
  if (is_object != object) return fail("an object and an array closed out of order");
  --depth_;
  put_char(bracket);
}

void JsonWriter::begin_object(const char* key) { open(key, '{', true); }
void JsonWriter::end_object() { close('}', true); }
void JsonWriter::begin_array(const char* key) { open(key, '[', false); }
void JsonWriter::end_array() { close(']', false); }

void JsonWriter::add(const char* key, const char* value) {
  if (value == nullptr) return add_null(key);
  value_start(key);
  put_string(value);
}

void JsonWriter::add(const char* key, bool value) {
  value_start(key);
  if (value) {
    put("true", 4);
  } else {
    put("false", 5);
  }
}

void JsonWriter::add(const char* key, uint64_t value) {
  value_start(key);
  char digits[24];
  const auto r = std::to_chars(digits, digits + sizeof(digits), value);
  put(digits, static_cast<size_t>(r.ptr - digits));
}

void JsonWriter::add(const char* key, int64_t value) {
  value_start(key);
  char digits[24];
  const auto r = std::to_chars(digits, digits + sizeof(digits), value);
  put(digits, static_cast<size_t>(r.ptr - digits));
}

void JsonWriter::add(const char* key, double value) {
  value_start(key);
  put_number(value);
}

void JsonWriter::add(const char* key, const Vec3& value) {
  value_start(key);
  put_char('[');
  put_number(value.x);
  put_char(',');
  put_number(value.y);
  put_char(',');
  put_number(value.z);
  put_char(']');
}

void JsonWriter::add_null(const char* key) {
  value_start(key);
  put("null", 4);
}

Status JsonWriter::finish() {
  if (status_.is_ok() && depth_ != 0) fail("a container left open");
  if (status_.is_ok() && !top_written_) fail("nothing written");
  flush();
  return status_;
}

}  // namespace splintcore

// Status: the one error type. Messages are built without the printf family so that the core
// links on bare-metal targets without it; numbers use std::to_chars (exact, locale-free).
#include <charconv>
#include <cstdio>
#include <cstdlib>

#include "splintcore/core.h"

namespace splintcore {

namespace {

// Hosted builds print the failed assertion; a core-only (firmware) build has no stdio and
// relies on the embedder's handler.
void default_assert_handler(const char* expression, const char* file, int line) {
#if defined(SPLINTCORE_WITH_PLATFORM)
  char number[16];
  auto r = std::to_chars(number, number + sizeof(number) - 1, line);
  *r.ptr = '\0';
  std::fputs("splintcore: assertion failed: ", stderr);
  std::fputs(expression, stderr);
  std::fputs(" (", stderr);
  std::fputs(file, stderr);
  std::fputs(":", stderr);
  std::fputs(number, stderr);
  std::fputs(")\n", stderr);
#else
  (void)expression;
  (void)file;
  (void)line;
#endif
}

AssertHandler g_assert_handler = default_assert_handler;  // set once at start-up by the embedder

// Appends text to a fixed buffer, truncating; returns the new length.
size_t append_bounded(char* buffer, size_t capacity, size_t length, const char* text, size_t n) {
  if (length + 1 >= capacity) return length;
  size_t room = capacity - 1 - length;
  size_t take = n < room ? n : room;
  std::memcpy(buffer + length, text, take);
  length += take;
  buffer[length] = '\0';
  return length;
}

}  // namespace

void set_assert_handler(AssertHandler handler) {
  g_assert_handler = handler != nullptr ? handler : default_assert_handler;
}

void assert_failed(const char* expression, const char* file, int line) {
  g_assert_handler(expression, file, line);
  std::abort();
}

const char* status_code_name(StatusCode code) {
  switch (code) {
    case StatusCode::kOk: return "ok";
    case StatusCode::kInvalidArgument: return "invalid_argument";
    case StatusCode::kArenaExhausted: return "arena_exhausted";
    case StatusCode::kParseError: return "parse_error";
    case StatusCode::kTruncated: return "truncated";
    case StatusCode::kNonFinite: return "non_finite";
    case StatusCode::kLimitExceeded: return "limit_exceeded";
    case StatusCode::kIoError: return "io_error";
    case StatusCode::kInvalidMesh: return "invalid_mesh";
    case StatusCode::kCancelled: return "cancelled";
    case StatusCode::kUnsupported: return "unsupported";
    case StatusCode::kInternal: return "internal";
  }
  return "unknown";
}

Status Status::error(StatusCode code, const char* message) {
  Status s;
  s.code_ = code;
  s.append(message);
  return s;
}

Status& Status::in_file(const char* name) {
  if (name == nullptr) return *this;
  size_t n = std::strlen(name);
  // Keep the end of a long path: the file name is the useful part.
  if (n >= kFileCapacity) {
    name += n - (kFileCapacity - 1);
    n = kFileCapacity - 1;
  }
  std::memcpy(file_, name, n);
  file_[n] = '\0';
  return *this;
}

Status& Status::append(const char* text) {
  return text != nullptr ? append(text, std::strlen(text)) : *this;
}

Status& Status::append(const char* text, size_t length) {
  message_length_ = static_cast<uint16_t>(
      append_bounded(message_, kMessageCapacity, message_length_, text, length));
  return *this;
}

Status& Status::append_u64(uint64_t value) {
  char digits[24];
  auto r = std::to_chars(digits, digits + sizeof(digits), value);
  return append(digits, static_cast<size_t>(r.ptr - digits));
}

Status& Status::append_i64(int64_t value) {
  char digits[24];
  auto r = std::to_chars(digits, digits + sizeof(digits), value);
  return append(digits, static_cast<size_t>(r.ptr - digits));
}

Status& Status::append_f64(double value) {
  char digits[32];
  auto r = std::to_chars(digits, digits + sizeof(digits), value);
  return append(digits, static_cast<size_t>(r.ptr - digits));
}

size_t Status::format(char* out, size_t cap) const {
  // Built in a local buffer with the same bounded appends, then copied.
  char text[kMessageCapacity + kFileCapacity + 96];
  size_t n = 0;
  auto put = [&](const char* s) { n = append_bounded(text, sizeof(text), n, s, std::strlen(s)); };
  auto put_u64 = [&](uint64_t v) {
    char d[24];
    auto r = std::to_chars(d, d + sizeof(d), v);
    n = append_bounded(text, sizeof(text), n, d, static_cast<size_t>(r.ptr - d));
  };
  text[0] = '\0';
  if (file_[0] != '\0') {
    put(file_);
    if (line_ != kNoPosition) {
      put(":");
      put_u64(line_);
      if (column_ != kNoPosition) {
        put(":");
        put_u64(column_);
      }
    }
    put(": ");
  } else if (line_ != kNoPosition) {
    put("line ");
    put_u64(line_);
    if (column_ != kNoPosition) {
      put(", column ");
      put_u64(column_);
    }
    put(": ");
  }
  if (byte_offset_ != kNoPosition) {
    put("byte ");
    put_u64(byte_offset_);
    put(": ");
  }
  put(message_);
  if (out != nullptr && cap > 0) {
    size_t take = n < cap - 1 ? n : cap - 1;
    std::memcpy(out, text, take);
    out[take] = '\0';
  }
  return n;
}

Status report_progress(const Context& ctx, const char* stage, uint64_t done, uint64_t total) {
  if (ctx.progress == nullptr || ctx.progress->report == nullptr) return Status::ok();
  if (ctx.progress->report(ctx.progress->user, stage, done, total)) return Status::ok();
  return make_error(StatusCode::kCancelled, "cancelled by the caller during ", stage);
}

}  // namespace splintcore

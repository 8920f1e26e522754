// Strict JSON parser (RFC 8259) into arena memory.
//
// Strict means: no comments, no trailing commas, no NaN/Infinity, no leading zeros or '+',
// no raw control characters in strings, valid UTF-8 only, no lone surrogates, no duplicate
// keys, one value per document. Recursion depth is bounded by JsonLimits::max_depth (at most
// 64), so the stack used is bounded too. Numbers are checked against the JSON grammar and then
// converted by std::from_chars, which rounds correctly and ignores the locale: the same text
// gives the same double on every platform.
#include <charconv>

#include "splintcore/json.h"

namespace splintcore {

const char* json_type_name(JsonType type) {
  switch (type) {
    case JsonType::kNull: return "null";
    case JsonType::kBool: return "boolean";
    case JsonType::kNumber: return "number";
    case JsonType::kString: return "string";
    case JsonType::kArray: return "array";
    case JsonType::kObject: return "object";
  }
  return "unknown";
}

namespace {

constexpr uint32_t kDepthCeiling = 64;

struct Parser {
  const Context* ctx = nullptr;
  const char* text = nullptr;
  size_t size = 0;
  size_t pos = 0;
  uint32_t line = 1;
  size_t line_start = 0;  // offset of the current line's first byte
  JsonLimits limits;
  const char* name = nullptr;
  ArenaArray<JsonValue>* values = nullptr;
  char* pool = nullptr;  // decoded strings
  size_t pool_used = 0;

  uint32_t column() const { return static_cast<uint32_t>(pos - line_start + 1); }

  Status error(const char* message) const {
    Status s = make_error(StatusCode::kParseError, message);
    s.at_line(line, column()).at_byte(pos);
    if (name != nullptr) s.in_file(name);
    return s;
  }
  // An error at an earlier byte of the current line (a string never spans lines, so the line
  // is right): escape errors point at the escape's backslash, not past it.
  Status error_at(size_t at, const char* message) {
    pos = at;
    return error(message);
  }
  Status error_found(const char* expected) const {
    Status s = make_error(StatusCode::kParseError, "expected ", expected);
    if (pos >= size) {
      s.append(", found the end of the input");
    } else {
      char c = text[pos];
      if (c >= 0x20 && c < 0x7f) {
        s.append(", found '");
        s.append(&c, 1);
        s.append("'");
      } else {
        s.append(", found byte ");
        s.append_u64(static_cast<uint8_t>(c));
      }
    }
    s.at_line(line, column()).at_byte(pos);
    if (name != nullptr) s.in_file(name);
    return s;
  }

  void skip_space() {
    while (pos < size) {
      char c = text[pos];
      if (c == '\n') {
        ++pos;
        ++line;
        line_start = pos;
      } else if (c == ' ' || c == '\t' || c == '\r') {
        ++pos;
      } else {
        break;
      }
    }
  }

  bool literal(const char* word) {
    size_t n = std::strlen(word);
    if (size - pos < n || std::memcmp(text + pos, word, n) != 0) return false;
    pos += n;
    return true;
  }

  Status new_value(JsonType type, uint32_t* index) {
    if (values->size() >= limits.max_values) {
      return make_error(StatusCode::kLimitExceeded, "JSON document has more than ",
                        limits.max_values, " values")
          .at_line(line, column())
          .in_file(name);
    }
    JsonValue v;
    v.type = type;
    v.line = line;
    v.column = column();
    if (!values->push_back(v)) return ctx->arena->exhausted_status();
    *index = static_cast<uint32_t>(values->size() - 1);
    return Status::ok();
  }

  void put_utf8(uint32_t cp) {
    char* out = pool + pool_used;
    if (cp < 0x80) {
      out[0] = static_cast<char>(cp);
      pool_used += 1;
    } else if (cp < 0x800) {
      out[0] = static_cast<char>(0xc0 | (cp >> 6));
      out[1] = static_cast<char>(0x80 | (cp & 0x3f));
      pool_used += 2;
    } else if (cp < 0x10000) {
      out[0] = static_cast<char>(0xe0 | (cp >> 12));
      out[1] = static_cast<char>(0x80 | ((cp >> 6) & 0x3f));
      out[2] = static_cast<char>(0x80 | (cp & 0x3f));
      pool_used += 3;
    } else {
      out[0] = static_cast<char>(0xf0 | (cp >> 18));
      out[1] = static_cast<char>(0x80 | ((cp >> 12) & 0x3f));
      out[2] = static_cast<char>(0x80 | ((cp >> 6) & 0x3f));
      out[3] = static_cast<char>(0x80 | (cp & 0x3f));
      pool_used += 4;
    }
  }

  bool hex4(uint32_t* out) {
    if (size - pos < 4) return false;
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) {
      char c = text[pos + static_cast<size_t>(i)];
      uint32_t d;
      if (c >= '0' && c <= '9')
        d = static_cast<uint32_t>(c - '0');
      else if (c >= 'a' && c <= 'f')
        d = static_cast<uint32_t>(c - 'a' + 10);
      else if (c >= 'A' && c <= 'F')
        d = static_cast<uint32_t>(c - 'A' + 10);
      else
        return false;
      v = v * 16 + d;
    }
    pos += 4;
    *out = v;
    return true;
  }

  // Parses a string at pos (which is '"'); the decoded bytes go to the pool.
  Status string(const char** out, uint32_t* length) {
    ++pos;  // opening quote
    const size_t start = pool_used;
    for (;;) {
      if (pos >= size) return error("unterminated string");
      const uint8_t c = static_cast<uint8_t>(text[pos]);
      if (c == '"') {
        ++pos;
        break;
      }
      if (c < 0x20) return error("control character in string (escape it)");
      if (c == '\\') {
        const size_t escape_at = pos;
        ++pos;
        if (pos >= size) return error_at(escape_at, "unterminated escape");
        const char e = text[pos++];
        switch (e) {
          case '"': pool[pool_used++] = '"'; break;
          case '\\': pool[pool_used++] = '\\'; break;
          case '/': pool[pool_used++] = '/'; break;
          case 'b': pool[pool_used++] = '\b'; break;
          case 'f': pool[pool_used++] = '\f'; break;
          case 'n': pool[pool_used++] = '\n'; break;
          case 'r': pool[pool_used++] = '\r'; break;
          case 't': pool[pool_used++] = '\t'; break;
          case 'u': {
            uint32_t cp = 0;
            if (!hex4(&cp)) return error_at(escape_at, "\\u needs four hex digits");
            if (cp >= 0xdc00 && cp <= 0xdfff) {
              return error_at(escape_at, "lone low surrogate in \\u escape");
            }
            if (cp >= 0xd800 && cp <= 0xdbff) {
              uint32_t low = 0;
              if (!(size - pos >= 2 && text[pos] == '\\' && text[pos + 1] == 'u')) {
                return error_at(escape_at, "high surrogate without a low surrogate");
              }
              pos += 2;
              if (!hex4(&low) || low < 0xdc00 || low > 0xdfff) {
                return error_at(escape_at, "high surrogate without a low surrogate");
              }
              cp = 0x10000 + ((cp - 0xd800) << 10) + (low - 0xdc00);
            }
            if (cp == 0) return error_at(escape_at, "\\u0000 is not allowed in strings");
            put_utf8(cp);
            break;
          }
          default: return error_at(escape_at, "invalid escape");
        }
        continue;
      }
      // Raw UTF-8: validate the sequence (shortest form, no surrogates, <= U+10FFFF).
      size_t n = c < 0x80                   ? 1
                 : (c >= 0xc2 && c <= 0xdf) ? 2
                 : (c >= 0xe0 && c <= 0xef) ? 3
                 : (c >= 0xf0 && c <= 0xf4) ? 4
                                            : 0;
      if (n == 0 || size - pos < n) return error("invalid UTF-8 in string");
      for (size_t k = 1; k < n; ++k) {
        if ((static_cast<uint8_t>(text[pos + k]) & 0xc0) != 0x80)
          return error("invalid UTF-8 in string");
      }
      if (n == 3) {
        uint8_t c1 = static_cast<uint8_t>(text[pos + 1]);
        if ((c == 0xe0 && c1 < 0xa0) || (c == 0xed && c1 >= 0xa0))
          return error("invalid UTF-8 in string");
      } else if (n == 4) {
        uint8_t c1 = static_cast<uint8_t>(text[pos + 1]);
        if ((c == 0xf0 && c1 < 0x90) || (c == 0xf4 && c1 >= 0x90))
          return error("invalid UTF-8 in string");
      }
      std::memcpy(pool + pool_used, text + pos, n);
      pool_used += n;
      pos += n;
    }
    pool[pool_used++] = '\0';
    *out = pool + start;
    *length = static_cast<uint32_t>(pool_used - start - 1);
    return Status::ok();
  }

  Status number(double* out) {
    const size_t start = pos;
    auto digits = [&]() {
      size_t d = pos;
      while (pos < size && text[pos] >= '0' && text[pos] <= '9') ++pos;
      return pos - d;
    };
    if (pos < size && text[pos] == '-') ++pos;
    if (pos < size && text[pos] == '0') {
      ++pos;
      if (pos < size && text[pos] >= '0' && text[pos] <= '9')
        return error("leading zero in number");
    } else if (digits() == 0) {
      return error_found("a digit");
    }
    if (pos < size && text[pos] == '.') {
      ++pos;
      if (digits() == 0) return error_found("a digit after the decimal point");
    }
    if (pos < size && (text[pos] == 'e' || text[pos] == 'E')) {
      ++pos;
      if (pos < size && (text[pos] == '+' || text[pos] == '-')) ++pos;
      if (digits() == 0) return error_found("a digit in the exponent");
    }
    auto r = std::from_chars(text + start, text + pos, *out, std::chars_format::general);
    if (r.ec == std::errc::result_out_of_range) {
      size_t end = pos;
      pos = start;
      Status s = error("number out of double range (overflow or underflow)");
      pos = end;
      return s;
    }
    if (r.ec != std::errc() || r.ptr != text + pos) return error("malformed number");
    return Status::ok();
  }

  int compare_keys(uint32_t a, uint32_t b) const {
    const JsonValue& x = (*values)[a];
    const JsonValue& y = (*values)[b];
    const uint32_t n = x.key_length < y.key_length ? x.key_length : y.key_length;
    const int c = n == 0 ? 0 : std::memcmp(x.key, y.key, n);
    if (c != 0) return c;
    return x.key_length < y.key_length ? -1 : (x.key_length > y.key_length ? 1 : 0);
  }

  uint32_t& next(uint32_t k) { return (*values)[k].next_sibling; }

  // Sorts the sibling list that starts at `head` (stable), and returns the new head: a
  // bottom-up merge sort of the links themselves (S. Tatham, "Mergesort for linked lists"),
  // so it takes no memory and does not recurse.
  template <class Less>
  uint32_t sort_siblings(uint32_t head, Less less) {
    for (uint64_t width = 1;; width *= 2) {
      uint32_t p = head, tail = kJsonNone;
      head = kJsonNone;
      uint64_t merges = 0;
      while (p != kJsonNone) {
        ++merges;
        uint32_t q = p;
        uint64_t p_size = 0;
        while (p_size < width && q != kJsonNone) {
          ++p_size;
          q = next(q);
        }
        uint64_t q_size = width;
        while (p_size > 0 || (q_size > 0 && q != kJsonNone)) {
          uint32_t e;
          if (p_size > 0 && (q_size == 0 || q == kJsonNone || !less(q, p))) {
            e = p;  // ties take the left run first: stable
            p = next(p);
            --p_size;
          } else {
            e = q;
            q = next(q);
            --q_size;
          }
          if (tail == kJsonNone) {
            head = e;
          } else {
            next(tail) = e;
          }
          tail = e;
        }
        p = q;
      }
      if (tail != kJsonNone) next(tail) = kJsonNone;
      if (merges <= 1) return head;
    }
  }

  // Duplicate keys are ambiguous (which one wins?): rejected once the object is complete. The
  // members are sorted by key, so this is O(n log n) key comparisons (comparing each key with
  // every earlier one took minutes on a hostile object of a few hundred thousand keys), and
  // then put back in document order (the order they were added in, so by index). No memory is
  // taken. Reports the first member, in document order, whose key repeats an earlier one.
  Status check_duplicate_keys(uint32_t object) {
    if ((*values)[object].child_count < 2) return Status::ok();
    auto by_key = [this](uint32_t a, uint32_t b) { return compare_keys(a, b) < 0; };
    uint32_t head = sort_siblings((*values)[object].first_child, by_key);
    uint32_t first = kJsonNone, repeat = kJsonNone;
    for (uint32_t k = head; next(k) != kJsonNone; k = next(k)) {
      if (next(k) < repeat && compare_keys(k, next(k)) == 0) {
        first = k;
        repeat = next(k);
      }
    }
    head = sort_siblings(head, [](uint32_t a, uint32_t b) { return a < b; });
    (*values)[object].first_child = head;
    if (repeat == kJsonNone) return Status::ok();
    const JsonValue& r = (*values)[repeat];
    const JsonValue& f = (*values)[first];
    return make_error(StatusCode::kParseError, "duplicate key \"", r.key,
                      "\" (first given at line ", f.line, ", column ", f.column, ")")
        .at_line(r.line, r.column)
        .in_file(name);
  }

  Status value(uint32_t depth, uint32_t* index) {
    skip_space();
    if (pos >= size) return error_found("a value");
    const char c = text[pos];
    if (c == '{' || c == '[') {
      if (depth >= limits.max_depth) {
        return make_error(StatusCode::kLimitExceeded, "JSON nesting deeper than ", limits.max_depth)
            .at_line(line, column())
            .in_file(name);
      }
      const bool object = c == '{';
      SPLINTCORE_RETURN_IF_ERROR(new_value(object ? JsonType::kObject : JsonType::kArray, index));
      const uint32_t self = *index;
      ++pos;
      skip_space();
      const char close = object ? '}' : ']';
      if (pos < size && text[pos] == close) {
        ++pos;
        return Status::ok();
      }
      uint32_t last = kJsonNone;
      for (;;) {
        const char* key = nullptr;
        uint32_t key_length = 0;
        if (object) {
          skip_space();
          if (pos >= size || text[pos] != '"') return error_found("a string key");
          SPLINTCORE_RETURN_IF_ERROR(string(&key, &key_length));
          skip_space();
          if (pos >= size || text[pos] != ':') return error_found("':'");
          ++pos;
        }
        uint32_t child = kJsonNone;
        SPLINTCORE_RETURN_IF_ERROR(value(depth + 1, &child));
        JsonValue& cv = (*values)[child];
        cv.key = key;
        cv.key_length = key_length;
        if (last == kJsonNone) {
          (*values)[self].first_child = child;
        } else {
          (*values)[last].next_sibling = child;
        }
        last = child;
        ++(*values)[self].child_count;
        skip_space();
        if (pos < size && text[pos] == ',') {
          ++pos;
          skip_space();
          if (pos < size && text[pos] == close) return error("trailing comma");
          continue;
        }
        if (pos < size && text[pos] == close) {
          ++pos;
          if (object) SPLINTCORE_RETURN_IF_ERROR(check_duplicate_keys(self));
          return Status::ok();
        }
        return error_found(object ? "',' or '}'" : "',' or ']'");
      }
    }
    if (c == '"') {
      SPLINTCORE_RETURN_IF_ERROR(new_value(JsonType::kString, index));
      const char* s = nullptr;
      uint32_t n = 0;
      SPLINTCORE_RETURN_IF_ERROR(string(&s, &n));
      (*values)[*index].string = s;
      (*values)[*index].length = n;
      return Status::ok();
    }
    if (c == '-' || (c >= '0' && c <= '9')) {
      SPLINTCORE_RETURN_IF_ERROR(new_value(JsonType::kNumber, index));
      double d = 0;
      SPLINTCORE_RETURN_IF_ERROR(number(&d));
      (*values)[*index].number = d;
      return Status::ok();
    }
    const size_t at = pos;
    if (literal("true") || literal("false")) {
      pos = at;
      SPLINTCORE_RETURN_IF_ERROR(new_value(JsonType::kBool, index));
      (*values)[*index].boolean = literal("true");
      if (!(*values)[*index].boolean) (void)literal("false");
      return Status::ok();
    }
    if (literal("null")) {
      pos = at;
      SPLINTCORE_RETURN_IF_ERROR(new_value(JsonType::kNull, index));
      (void)literal("null");
      return Status::ok();
    }
    return error_found("a value");
  }
};

}  // namespace

const JsonValue* JsonDocument::member(const JsonValue& object, const char* key) const {
  if (object.type != JsonType::kObject) return nullptr;
  for (uint32_t k = object.first_child; k != kJsonNone; k = values[k].next_sibling) {
    if (std::strcmp(values[k].key, key) == 0) return &values[k];
  }
  return nullptr;
}

Status json_error(const JsonDocument& doc, const JsonValue& at, StatusCode code,
                  const char* message) {
  Status s = Status::error(code, message);
  s.at_line(at.line, at.column);
  if (doc.name != nullptr) s.in_file(doc.name);
  return s;
}

// The string pool, then the values. Every value but the root follows its own '[', ',' or ':'
// and takes at least one byte of its own; a '[' can be both an array's first byte and its first
// element's separator, but a complete array then closes with a ']' that is neither, and at
// most max_depth arrays are open when the text ends. So 2 * values <= length + 1 + max_depth.
uint64_t parse_json_bound(uint64_t length, const JsonLimits& limits) {
  const uint64_t depth = limits.max_depth > kDepthCeiling ? kDepthCeiling : limits.max_depth;
  uint64_t values = (length + 1 + depth) / 2 + 1;
  if (values > limits.max_values) values = limits.max_values;
  return arena_array_bound<char>(length + 1) + arena_array_bound<JsonValue>(values);
}

Status parse_json(const Context& ctx, const char* text, size_t length, const JsonLimits& limits,
                  const char* name, JsonDocument* out) {
  if (length > limits.max_bytes) {
    return make_error(StatusCode::kLimitExceeded, "JSON document is ", length,
                      " bytes, over the limit of ", limits.max_bytes)
        .in_file(name);
  }
  Parser p;
  p.ctx = &ctx;
  p.text = text;
  p.size = length;
  p.limits = limits;
  if (p.limits.max_depth > kDepthCeiling) p.limits.max_depth = kDepthCeiling;
  p.name = name;
  // Decoded strings never exceed their source text, plus a NUL each: one pool of
  // length + 1 bytes is enough, and the value array then grows alone at the arena's top.
  ArenaScope scope(*ctx.arena);  // a failed parse leaves nothing behind
  p.pool = ctx.arena->allocate_array<char>(length + 1);
  if (p.pool == nullptr) return ctx.arena->exhausted_status();
  ArenaArray<JsonValue> values(ctx.arena);
  p.values = &values;
  // Skip a UTF-8 byte order mark: editors on some platforms write one.
  if (length >= 3 && static_cast<uint8_t>(text[0]) == 0xef &&
      static_cast<uint8_t>(text[1]) == 0xbb && static_cast<uint8_t>(text[2]) == 0xbf) {
    p.pos = 3;
    p.line_start = 3;
  }
  uint32_t root = 0;
  Status s = p.value(0, &root);
  if (s.is_ok()) {
    p.skip_space();
    if (p.pos != p.size) s = p.error("unexpected data after the JSON value");
  }
  if (!s.is_ok()) return s;
  scope.commit();
  out->values = Span<const JsonValue>(values.data(), values.size());
  out->name = name;
  return Status::ok();
}

}  // namespace splintcore

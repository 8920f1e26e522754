// Shared parts of the CT readers: windowed reading, header text, numbers, budgets and the
// stored value -> Hounsfield unit conversion of DICOM PS3.3 C.11.1.1.2 (Modality LUT,
// HU = Rescale Slope * SV + Rescale Intercept), applied to all three formats.
#include "ct/ct_common.h"

#include <charconv>
#include <cmath>

namespace splintcore {

const char* ct_format_name(CtFormat format) {
  switch (format) {
    case CtFormat::kDicom: return "dicom";
    case CtFormat::kNrrd: return "nrrd";
    case CtFormat::kMetaImage: return "metaimage";
    default: return "unknown";
  }
}

namespace {
Status memory_open(void* user, const char* name, ByteSource* out) {
  CtMemoryFiles* m = static_cast<CtMemoryFiles*>(user);
  for (uint32_t i = 0; i < m->count; ++i) {
    if (m->files[i].name != nullptr && std::strcmp(m->files[i].name, name) == 0) {
      m->current = MemorySource{m->files[i].data, m->files[i].size, 0, m->max_chunk};
      *out = memory_source(&m->current, m->files[i].name);
      return Status::ok();
    }
  }
  return make_error(StatusCode::kIoError, "cannot open \"", name, "\": no such file").in_file(name);
}
void memory_close(void* user, ByteSource* source) {
  (void)source;
  static_cast<CtMemoryFiles*>(user)->current = MemorySource{};
}
Status memory_open_index(void* user, uint32_t index, ByteSource* out) {
  CtMemoryFiles* m = static_cast<CtMemoryFiles*>(user);
  if (index >= m->count) {
    return make_error(StatusCode::kIoError, "no file ", index, " in the series");
  }
  m->current = MemorySource{m->files[index].data, m->files[index].size, 0, m->max_chunk};
  *out =
      memory_source(&m->current, m->files[index].name != nullptr ? m->files[index].name : "memory");
  return Status::ok();
}
void memory_close_index(void* user, uint32_t index, ByteSource* source) {
  (void)index;
  memory_close(user, source);
}
}  // namespace

CtFileOpener ct_memory_opener(CtMemoryFiles* files) {
  CtFileOpener o;
  o.open = memory_open;
  o.close = memory_close;
  o.user = files;
  return o;
}

CtSeries ct_memory_series(CtMemoryFiles* files) {
  CtSeries s;
  s.count = files->count;
  s.open = memory_open_index;
  s.close = memory_close_index;
  s.user = files;
  return s;
}

namespace ct_detail {

void Reader::rebuffer(uint8_t* buffer, size_t capacity) {
  const size_t left = available();
  SPLINTCORE_ASSERT(left <= capacity);
  if (left > 0) std::memmove(buffer, buf + pos, left);
  base += pos;
  buf = buffer;
  cap = capacity;
  pos = 0;
  end = left;
}

Status Reader::skip(uint64_t n, const char* what) {
  while (n > 0) {
    if (available() == 0) {
      SPLINTCORE_RETURN_IF_ERROR(fill(1));
      if (available() == 0) {
        return make_error(StatusCode::kTruncated, "file ends inside ", what, " (", n,
                          " more bytes expected)")
            .at_byte(offset());
      }
    }
    size_t take = available();
    if (take > n) take = static_cast<size_t>(n);
    pos += take;
    n -= take;
  }
  return Status::ok();
}

Status Reader::read_line(char* line, size_t* length, bool* too_long, bool* got_line,
                         uint64_t* budget) {
  *length = 0;
  *too_long = false;
  *got_line = false;
  bool any = false;
  for (;;) {
    if (available() == 0) {
      SPLINTCORE_RETURN_IF_ERROR(fill(1));
      if (available() == 0) break;
    }
    if (*budget == 0) {
      return make_error(StatusCode::kLimitExceeded,
                        "header longer than the limit (CtReadOptions::max_header_bytes)")
          .at_byte(offset());
    }
    --*budget;
    const char c = static_cast<char>(buf[pos++]);
    any = true;
    if (c == '\n') break;
    if (*length + 1 < kLineCapacity) {
      line[(*length)++] = c;
    } else {
      *too_long = true;
    }
  }
  if (*length > 0 && line[*length - 1] == '\r' && !*too_long) --*length;
  line[*length] = '\0';
  *got_line = any;
  return Status::ok();
}

Status in_source(Status s, const ByteSource& source) {
  if (source.name != nullptr && s.file()[0] == '\0') s.in_file(source.name);
  return s;
}

bool equal_nocase(const char* a, size_t an, const char* b) {
  const size_t bn = std::strlen(b);
  if (an != bn) return false;
  for (size_t i = 0; i < an; ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = static_cast<char>(x - 'A' + 'a');
    if (y >= 'A' && y <= 'Z') y = static_cast<char>(y - 'A' + 'a');
    if (x != y) return false;
  }
  return true;
}

void trim(const char** text, size_t* length) {
  const char* t = *text;
  size_t n = *length;
  while (n > 0 && (t[0] == ' ' || t[0] == '\t' || t[0] == '\0')) {
    ++t;
    --n;
  }
  while (n > 0 && (t[n - 1] == ' ' || t[n - 1] == '\t' || t[n - 1] == '\0' || t[n - 1] == '\r')) {
    --n;
  }
  *text = t;
  *length = n;
}

bool parse_double(const char* text, size_t length, double* out) {
  trim(&text, &length);
  if (length == 0 || length > 64) return false;
  if (text[0] == '+') {
    ++text;
    --length;
    if (length == 0 || text[0] == '-' || text[0] == '+') return false;
  }
  for (size_t i = 0; i < length; ++i) {
    const char c = text[i];
    const bool ok =
        (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E';
    if (!ok) return false;
  }
  double v = 0;
  auto r = std::from_chars(text, text + length, v, std::chars_format::general);
  if (r.ec != std::errc() || r.ptr != text + length || !is_finite(v)) return false;
  *out = v;
  return true;
}

bool parse_i64(const char* text, size_t length, int64_t* out) {
  trim(&text, &length);
  if (length > 0 && text[0] == '+') {
    ++text;
    --length;
  }
  if (length == 0 || length > 24) return false;
  int64_t v = 0;
  auto r = std::from_chars(text, text + length, v, 10);
  if (r.ec != std::errc() || r.ptr != text + length) return false;
  *out = v;
  return true;
}

bool parse_doubles(const char* text, size_t length, char extra, double* out, size_t max,
                   size_t* count) {
  *count = 0;
  size_t i = 0;
  if (extra != '\0') {
    trim(&text, &length);
    if (length == 0) return true;
    for (;;) {
      size_t j = i;
      while (j < length && text[j] != extra) ++j;
      if (*count == max) return false;
      if (!parse_double(text + i, j - i, &out[*count])) return false;
      ++*count;
      if (j == length) return true;
      i = j + 1;
    }
  }
  for (;;) {
    while (i < length && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i == length) return true;
    size_t j = i;
    while (j < length && text[j] != ' ' && text[j] != '\t') ++j;
    if (*count == max) return false;
    if (!parse_double(text + i, j - i, &out[*count])) return false;
    ++*count;
    i = j;
  }
}

Status check_size(uint64_t nx, uint64_t ny, uint64_t nz, const CtReadOptions& options,
                  uint64_t* voxel_bytes) {
  const uint64_t n[3] = {nx, ny, nz};
  const char* names[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (n[a] == 0) {
      return make_error(StatusCode::kParseError, "size along ", names[a], " is 0");
    }
    if (n[a] > options.max_dimension) {
      return make_error(StatusCode::kLimitExceeded, "size along ", names[a], " is ", n[a],
                        ", more than the limit ", options.max_dimension,
                        " (CtReadOptions::max_dimension)");
    }
  }
  uint64_t voxels = 0, bytes = 0;
  if (!checked_mul(nx, ny, &voxels) || !checked_mul(voxels, nz, &voxels) ||
      voxels > options.max_voxels) {
    return make_error(StatusCode::kLimitExceeded, "volume of ", nx, " x ", ny, " x ", nz,
                      " voxels is more than the limit ", options.max_voxels,
                      " (CtReadOptions::max_voxels)");
  }
  if (!checked_mul(voxels, 2, &bytes) || bytes > SIZE_MAX) {
    return make_error(StatusCode::kLimitExceeded, "volume of ", voxels,
                      " voxels does not fit in memory on this platform");
  }
  *voxel_bytes = bytes;
  return Status::ok();
}

// Refuses up front only what cannot fit: the voxels and temporaries themselves. The alignment
// padding (up to 16 bytes an allocation) is in the need the message gives, not in the test,
// so that an arena of exactly a first read's high water (the two-step contract) is enough.
Status check_budget(const Arena& arena, uint64_t voxel_bytes, uint64_t temporaries,
                    uint32_t allocations) {
  uint64_t bare = 0, need = 0;
  const uint64_t free_bytes = arena.cap() > arena.used() ? arena.cap() - arena.used() : 0;
  if (!checked_add(voxel_bytes, temporaries, &bare) ||
      !checked_add(bare, uint64_t{Arena::kDefaultAlignment} * allocations, &need) ||
      bare > free_bytes) {
    uint64_t total = 0;
    if (!checked_add(arena.used(), need, &total)) total = ~uint64_t{0};
    return make_error(StatusCode::kArenaExhausted, "arena exhausted: reading the volume needs ",
                      need, " bytes (", voxel_bytes, " for the voxels), ", free_bytes,
                      " are free (cap ", arena.cap(), "); increase the memory cap to at least ",
                      total, " bytes");
  }
  return Status::ok();
}

Status check_spacing(double value, const char* axis, const CtReadOptions& options) {
  if (!is_finite(value) || !(value > 0)) {
    return make_error(StatusCode::kParseError, "spacing along ", axis, " is ", value,
                      ": must be a positive number of mm");
  }
  if (value < options.min_spacing || value > options.max_spacing) {
    return make_error(StatusCode::kParseError, "spacing along ", axis, " is ", value,
                      " mm, outside [", options.min_spacing, ", ", options.max_spacing,
                      "] mm: wrong units?");
  }
  return Status::ok();
}

Status check_axes(Vec3* x, Vec3* y, Vec3* z, const CtReadOptions& options) {
  Vec3* axes[3] = {x, y, z};
  const char* names[3] = {"x", "y", "z"};
  const double tol = options.orientation_tolerance;
  // x, y, their dot product, then z (for DICOM z is x cross y: told last).
  const int order[6][2] = {{0, 0}, {1, 1}, {0, 1}, {2, 2}, {0, 2}, {1, 2}};
  for (const auto& pair : order) {
    const int a = pair[0], b = pair[1];
    if (a == b) {
      if (!is_finite(*axes[a])) {
        return make_error(StatusCode::kParseError, "direction of axis ", names[a],
                          " is not finite");
      }
      const double len = length(*axes[a]);
      if (!(std::fabs(len - 1.0) <= tol)) {
        return make_error(StatusCode::kParseError, "direction of axis ", names[a], " has length ",
                          len, ", not 1 (tolerance ", tol, ")");
      }
      continue;
    }
    const double d = dot(*axes[a], *axes[b]);
    if (!(std::fabs(d) <= tol)) {
      return make_error(StatusCode::kParseError, "directions of axes ", names[a], " and ", names[b],
                        " are not orthogonal (dot product ", d, ", tolerance ", tol, ")");
    }
  }
  for (int a = 0; a < 3; ++a) {
    const double len = length(*axes[a]);
    *axes[a] = Vec3{axes[a]->x / len, axes[a]->y / len, axes[a]->z / len};
  }
  return Status::ok();
}

void describe_type(const VoxelFormat& f, CtInfo* info) {
  const char* name = "int16";
  if (f.is_float) {
    name = f.bytes == 4 ? "float32" : "float64";
  } else if (f.bytes == 1) {
    name = f.is_signed ? "int8" : "uint8";
  } else if (f.bytes == 2) {
    name = f.is_signed ? "int16" : "uint16";
  } else {
    name = f.is_signed ? "int32" : "uint32";
  }
  std::memset(info->stored_type, 0, sizeof(info->stored_type));
  std::memcpy(info->stored_type, name, std::strlen(name));
  info->big_endian = f.big_endian;
  info->bits_stored = f.bits_stored != 0 ? f.bits_stored : static_cast<uint8_t>(f.bytes * 8);
}

int16_t to_hu(double value, double slope, double intercept, bool* clamped) {
  const double scaled = slope * value;
  const double v = scaled + intercept;
  *clamped = false;
  if (!(v < 32767.5)) {  // also +inf
    *clamped = true;
    return 32767;
  }
  if (!(v >= -32768.5)) {
    *clamped = true;
    return -32768;
  }
  const double r = std::round(v);  // halves away from zero; exact, the same everywhere
  if (r > 32767.0) {
    *clamped = true;
    return 32767;
  }
  if (r < -32768.0) {
    *clamped = true;
    return -32768;
  }
  return static_cast<int16_t>(static_cast<int32_t>(r));
}

namespace {

inline uint64_t load(const uint8_t* p, unsigned bytes, bool big_endian) {
  uint64_t v = 0;
  if (big_endian) {
    for (unsigned i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  } else {
    for (unsigned i = bytes; i-- > 0;) v = (v << 8) | p[i];
  }
  return v;
}

// An integer HU value as int16 (saturated; each saturation counted in *clamped).
int16_t clamped_hu(int64_t h, uint64_t* clamped) {
  if (h > 32767) {
    ++*clamped;
    return 32767;
  }
  if (h < -32768) {
    ++*clamped;
    return -32768;
  }
  return static_cast<int16_t>(h);
}

// The common case (16-bit little endian, no scaling): the same results as the general loop of
// convert_voxels(), faster. Returns how many values were clamped.
uint64_t convert_plain_le16(const uint8_t* p, uint64_t n, bool is_signed, int64_t int_intercept,
                            int16_t* o) {
  uint64_t clamped_count = 0;
  for (uint64_t k = 0; k < n; ++k) {
    const uint32_t u = uint32_t{p[2 * k]} | (uint32_t{p[2 * k + 1]} << 8);
    const int64_t value =
        is_signed ? static_cast<int64_t>(static_cast<int16_t>(u)) : static_cast<int64_t>(u);
    o[k] = clamped_hu(value + int_intercept, &clamped_count);
  }
  return clamped_count;
}

}  // namespace

Status convert_voxels(Reader& reader, const VoxelFormat& f, uint64_t count, double slope,
                      double intercept, int16_t* out, uint64_t first_index, uint64_t* saturated) {
  const unsigned bytes = f.bytes;
  const unsigned width = bytes * 8;
  const unsigned bits = (f.bits_stored != 0 && f.bits_stored < width) ? f.bits_stored : width;
  const uint64_t mask = bits == 64 ? ~uint64_t{0} : (uint64_t{1} << bits) - 1;
  // Integers with slope 1 and an integer intercept: exact in int64, the same as the double path.
  const bool integer_path = !f.is_float && slope == 1.0 && intercept == std::floor(intercept) &&
                            std::fabs(intercept) < 2147483648.0 && bits <= 32;
  const int64_t int_intercept = integer_path ? static_cast<int64_t>(intercept) : 0;
  const size_t block = reader.cap - reader.cap % bytes;
  uint64_t done = 0;
  uint64_t clamped_count = 0;
  while (done < count) {
    const uint64_t remaining_bytes = (count - done) * bytes;
    const size_t want = remaining_bytes < block ? static_cast<size_t>(remaining_bytes) : block;
    SPLINTCORE_RETURN_IF_ERROR(reader.fill(want));
    uint64_t n = reader.available() / bytes;
    if (n > count - done) n = count - done;
    if (n == 0) {
      return make_error(StatusCode::kTruncated, "voxel data ends early: ", count - done, " of ",
                        count, " values missing")
          .at_byte(reader.base + reader.end);
    }
    const uint8_t* p = reader.buf + reader.pos;
    int16_t* o = out + done;
    if (integer_path && bytes == 2 && bits == 16 && !f.big_endian) {
      clamped_count += convert_plain_le16(p, n, f.is_signed, int_intercept, o);
      reader.pos += static_cast<size_t>(n * 2);
      done += n;
      continue;
    }
    for (uint64_t k = 0; k < n; ++k, p += bytes) {
      const uint64_t raw = load(p, bytes, f.big_endian);
      if (f.is_float) {
        double v;
        if (bytes == 4) {
          const uint32_t b32 = static_cast<uint32_t>(raw);
          float fv;
          std::memcpy(&fv, &b32, 4);
          if (!is_finite(fv)) {
            return make_error(StatusCode::kNonFinite, "voxel ", first_index + done + k,
                              " is NaN or infinite")
                .at_index(first_index + done + k)
                .at_byte(reader.offset() + k * bytes);
          }
          v = static_cast<double>(fv);
        } else {
          std::memcpy(&v, &raw, 8);
          if (!is_finite(v)) {
            return make_error(StatusCode::kNonFinite, "voxel ", first_index + done + k,
                              " is NaN or infinite")
                .at_index(first_index + done + k)
                .at_byte(reader.offset() + k * bytes);
          }
        }
        bool c = false;
        o[k] = to_hu(v, slope, intercept, &c);
        clamped_count += c ? 1u : 0u;
        continue;
      }
      uint64_t u = raw & mask;
      int64_t value;
      if (f.is_signed && bits < 64 && (u >> (bits - 1)) != 0) {
        value = static_cast<int64_t>(u) - static_cast<int64_t>(uint64_t{1} << bits);
      } else {
        value = static_cast<int64_t>(u);
      }
      if (integer_path) {
        o[k] = clamped_hu(value + int_intercept, &clamped_count);
      } else {
        bool c = false;
        o[k] = to_hu(static_cast<double>(value), slope, intercept, &c);
        clamped_count += c ? 1u : 0u;
      }
    }
    reader.pos += static_cast<size_t>(n * bytes);
    done += n;
  }
  *saturated += clamped_count;
  return Status::ok();
}

size_t chunk_size(const CtReadOptions& options) {
  // At least the header window: attached data may already be in it when the chunk takes over.
  size_t c = options.chunk_bytes - options.chunk_bytes % 8;
  return c < kHeaderWindow ? kHeaderWindow : c;
}

namespace {

// The volume's size against the limits: *voxels and the *data_bytes they take in the file.
// Attached data shorter than the header says is a truncation, told before any allocation.
Status check_raw_size(const Reader& header, const ByteSource& header_source, const RawData& data,
                      const CtReadOptions& options, uint64_t* voxels, uint64_t* data_bytes) {
  uint64_t voxel_bytes = 0;
  SPLINTCORE_RETURN_IF_ERROR(
      in_source(check_size(data.nx, data.ny, data.nz, options, &voxel_bytes), header_source));
  *voxels = voxel_bytes / 2;
  if (!checked_mul(*voxels, data.format.bytes, data_bytes)) {
    return in_source(make_error(StatusCode::kLimitExceeded, "voxel data too large"), header_source);
  }
  if (data.data_file == nullptr && header_source.size != kUnknownSize && !data.gzip) {
    uint64_t end = 0;
    if (!checked_add(header.offset(), *data_bytes, &end) || end > header_source.size) {
      return in_source(make_error(StatusCode::kTruncated, "the voxel data needs ", *data_bytes,
                                  " bytes from byte ", header.offset(), ", the file has only ",
                                  header_source.size)
                           .at_byte(header_source.size),
                       header_source);
    }
  }
  return Status::ok();
}

// Where the voxel data is read from: the header's own reader (attached data, moved into the
// chunk) or the data file, opened through the opener (closed when this goes out of scope).
struct DataInput {
  OpenedFile opened;
  Reader detached;
  Reader* reader = nullptr;
  const ByteSource* source = nullptr;

  Status open(Reader& header, const ByteSource& header_source, const CtFileOpener* opener,
              const char* data_file, uint8_t* chunk, size_t chunk_bytes) {
    if (data_file == nullptr) {
      header.rebuffer(chunk, chunk_bytes);
      reader = &header;
      source = &header_source;
      return Status::ok();
    }
    if (opener == nullptr || opener->open == nullptr) {
      return in_source(make_error(StatusCode::kInvalidArgument, "the data is in \"", data_file,
                                  "\" but no file opener was given"),
                       header_source);
    }
    opened.opener = opener;
    Status s = opener->open(opener->user, data_file, &opened.source);
    if (!s.is_ok()) {
      if (s.file()[0] == '\0') s.in_file(data_file);
      return s;
    }
    opened.open = true;
    if (opened.source.name == nullptr) opened.source.name = data_file;
    detached.init(&opened.source, chunk, chunk_bytes);
    reader = &detached;
    source = &opened.source;
    return Status::ok();
  }
};

// True when fewer than `data_bytes` bytes follow the reader's position in a file of known size.
bool data_cut_short(const ByteSource& source, const Reader& reader, uint64_t data_bytes) {
  return source.size != kUnknownSize &&
         (source.size < reader.offset() || source.size - reader.offset() < data_bytes);
}

// Line skip, then byte skip (-1: the data is the last data_bytes of the file); then the data
// must fit in what is left of a file of known size.
Status skip_to_voxels(Reader& reader, const ByteSource& source, const RawData& data,
                      uint64_t data_bytes) {
  for (uint64_t l = 0; l < data.line_skip; ++l) {
    for (;;) {
      if (reader.available() == 0) {
        SPLINTCORE_RETURN_IF_ERROR(reader.fill(1));
        if (reader.available() == 0) {
          return make_error(StatusCode::kTruncated, "file ends while skipping line ", l + 1, " of ",
                            data.line_skip, " (line skip)")
              .at_byte(reader.offset());
        }
      }
      if (reader.buf[reader.pos++] == '\n') break;
    }
  }
  uint64_t skip = 0;
  if (data.byte_skip == -1) {
    if (source.size == kUnknownSize) {
      return make_error(StatusCode::kUnsupported,
                        "byte skip -1 needs the data file's size, which its source does not know");
    }
    if (data_cut_short(source, reader, data_bytes)) {
      return make_error(StatusCode::kTruncated, "the voxel data needs ", data_bytes,
                        " bytes, the file has ", source.size)
          .at_byte(source.size);
    }
    skip = source.size - reader.offset() - data_bytes;
  } else {
    skip = static_cast<uint64_t>(data.byte_skip);
  }
  SPLINTCORE_RETURN_IF_ERROR(reader.skip(skip, "the bytes skipped before the voxel data"));
  if (data_cut_short(source, reader, data_bytes)) {
    return make_error(StatusCode::kTruncated, "the voxel data needs ", data_bytes,
                      " bytes from byte ", reader.offset(), ", the file has only ", source.size)
        .at_byte(source.size);
  }
  return Status::ok();
}

// Gzip data: the line skip in the file, then the stream inflated through a second chunk (byte
// skip in inflated bytes), converted as it comes.
Status read_gzip_voxels(Arena& arena, DataInput& input, const RawData& data, size_t chunk,
                        uint64_t voxels, int16_t* voxels_out, uint64_t* clamped) {
  if (data.byte_skip < 0) {
    return make_error(StatusCode::kUnsupported, "byte skip -1 with gzip encoding");
  }
  RawData lines_only = data;
  lines_only.byte_skip = 0;
  SPLINTCORE_RETURN_IF_ERROR(skip_to_voxels(*input.reader, *input.source, lines_only, 0));
  InflatingSource z;
  z.compressed = input.reader;
  z.stream_start = input.reader->offset();
  z.name = input.source->name;
  SPLINTCORE_RETURN_IF_ERROR(z.inflater.begin(arena, ZFormat::kGzip));
  uint8_t* buffer = arena.allocate_array<uint8_t>(chunk);
  if (buffer == nullptr) return arena.exhausted_status();
  const ByteSource inflated = z.source();
  Reader reader;
  reader.init(&inflated, buffer, chunk);
  Status s = reader.skip(static_cast<uint64_t>(data.byte_skip),
                         "the inflated bytes skipped before the voxel data");
  if (s.is_ok()) s = convert_voxels(reader, data.format, voxels, 1.0, 0.0, voxels_out, 0, clamped);
  if (!z.error.is_ok()) return z.error;  // the stream's own error, not "read failed"
  if (s.code() == StatusCode::kTruncated) {
    return make_error(StatusCode::kTruncated, "the gzip data inflates to ", reader.offset(),
                      " bytes, fewer than the ",
                      voxels * data.format.bytes + static_cast<uint64_t>(data.byte_skip),
                      " the header describes")
        .at_byte(z.stream_start + z.inflater.total_in());
  }
  return s;
}

}  // namespace

int64_t InflatingSource::read(void* user, uint8_t* buffer, size_t capacity) {
  InflatingSource& z = *static_cast<InflatingSource*>(user);
  uint8_t* out = buffer;
  size_t room = capacity;
  while (room == capacity) {
    Reader& r = *z.compressed;
    Status s = r.available() == 0 ? r.fill(1) : Status::ok();
    const uint8_t* p = r.buf + r.pos;
    size_t n = r.available();
    if (s.is_ok()) s = z.inflater.run(&p, &n, &out, &room);
    r.pos = static_cast<size_t>(p - r.buf);
    // The end: a finished stream with input it refused, or with the file used up. (A gzip
    // member that ends where the buffered input does may be followed by another: read on.)
    if (s.is_ok() && room == capacity && z.inflater.finished() && (r.available() > 0 || r.at_eof)) {
      return 0;
    }
    if (s.is_ok() && room == capacity && r.available() == 0 && r.at_eof) {
      s = z.inflater.end_of_input();
    }
    if (!s.is_ok()) {
      if (s.byte_offset() != kNoPosition) s.at_byte(z.stream_start + s.byte_offset());
      z.error = s;
      return -1;
    }
  }
  return static_cast<int64_t>(capacity - room);
}

ByteSource InflatingSource::source() {
  ByteSource b;
  b.read = &InflatingSource::read;
  b.user = this;
  b.name = name;
  return b;
}

Status read_raw_volume(const Context& ctx, Reader& header, const ByteSource& header_source,
                       const CtFileOpener* opener, const RawData& data,
                       const CtReadOptions& options, int16_t** hu, uint64_t* saturated) {
  Arena& arena = *ctx.arena;
  uint64_t voxels = 0, data_bytes = 0;
  SPLINTCORE_RETURN_IF_ERROR(
      check_raw_size(header, header_source, data, options, &voxels, &data_bytes));
  const size_t chunk = chunk_size(options);
  if (data.gzip) {  // a second chunk for the inflated bytes, and the inflater
    SPLINTCORE_RETURN_IF_ERROR(
        check_budget(arena, voxels * 2,
                     uint64_t{chunk} * 2 + inflate_state_bytes() - (Arena::kDefaultAlignment - 1),
                     3));  // (the padding inflate_state_bytes() allows for is counted by 3)
  } else {
    SPLINTCORE_RETURN_IF_ERROR(check_budget(arena, voxels * 2, chunk, 2));
  }

  DataInput input;          // declared first: a data file is closed after the arena is rewound
  ArenaScope scope(arena);  // on an error the arena is as it was
  int16_t* voxels_out = arena.allocate_array<int16_t>(static_cast<size_t>(voxels));
  if (voxels_out == nullptr) return arena.exhausted_status();
  ArenaScope chunk_scope(arena);  // the read chunk is a temporary, also on success
  uint8_t* buffer = arena.allocate_array<uint8_t>(chunk);
  if (buffer == nullptr) return arena.exhausted_status();
  SPLINTCORE_RETURN_IF_ERROR(
      input.open(header, header_source, opener, data.data_file, buffer, chunk));

  uint64_t clamped = 0;
  if (data.gzip) {
    Status s = read_gzip_voxels(arena, input, data, chunk, voxels, voxels_out, &clamped);
    if (!s.is_ok()) return in_source(s, *input.source);
    scope.commit();  // the chunks and the inflater go with chunk_scope
    *hu = voxels_out;
    *saturated = clamped;
    return Status::ok();
  }
  Status s = skip_to_voxels(*input.reader, *input.source, data, data_bytes);
  if (s.is_ok()) {
    s = convert_voxels(*input.reader, data.format, voxels, 1.0, 0.0, voxels_out, 0, &clamped);
  }
  if (!s.is_ok()) return in_source(s, *input.source);
  scope.commit();
  *hu = voxels_out;
  *saturated = clamped;
  return Status::ok();
}

Status read_text_volume(const Context& ctx, Reader& header, const ByteSource& header_source,
                        const CtFileOpener* opener, const CtReadOptions& options,
                        const TextVolume& volume, CtInfo found, CtVolume* out, CtInfo* info) {
  Vec3 axes[3] = {volume.axes[0], volume.axes[1], volume.axes[2]};
  const char* names[3] = {"x", "y", "z"};
  Status s;
  for (int a = 0; a < 3 && s.is_ok(); ++a) s = check_spacing(volume.spacing[a], names[a], options);
  if (s.is_ok()) s = check_axes(&axes[0], &axes[1], &axes[2], options);
  if (!s.is_ok()) {
    s.at_line(volume.geometry_line);
    return in_source(s, header_source);
  }

  const RawData& data = volume.data;
  int16_t* hu = nullptr;
  uint64_t saturated = 0;
  SPLINTCORE_RETURN_IF_ERROR(
      read_raw_volume(ctx, header, header_source, opener, data, options, &hu, &saturated));
  out->nx = data.nx;
  out->ny = data.ny;
  out->nz = data.nz;
  out->spacing = volume.spacing;
  out->origin = volume.origin;
  out->axis_x = axes[0];
  out->axis_y = axes[1];
  out->axis_z = axes[2];
  out->hu = hu;
  out->saturated = saturated;
  if (info != nullptr) {
    found.nx = data.nx;
    found.ny = data.ny;
    found.nz = data.nz;
    found.spacing = volume.spacing;
    describe_type(data.format, &found);
    found.slice_count = data.nz;
    found.detached = data.data_file != nullptr;
    found.saturated = saturated;
    *info = found;
  }
  return Status::ok();
}

// ---- JPEG marker segments (T.81 Annex B) ----------------------------------------------------

Status JpegMarkers::error(StatusCode code, const char* what, uint64_t at) const {
  return make_error(code, codec, ": ", what).at_byte(at);
}

Status JpegMarkers::start(const char* stream) {
  if (size < 2 || data[0] != 0xFF || data[1] != 0xD8) {
    return make_error(StatusCode::kParseError, codec, ": not a ", stream, " stream (no SOI marker)")
        .at_byte(0);
  }
  pos = 2;
  return Status::ok();
}

Status JpegMarkers::next_marker(uint32_t* code, size_t* at) {
  *at = pos;
  if (pos >= size) return error(StatusCode::kTruncated, "data ends before EOI", size);
  if (data[pos] != 0xFF) return error(StatusCode::kParseError, "expected a marker", pos);
  while (pos < size && data[pos] == 0xFF) ++pos;
  if (pos >= size) return error(StatusCode::kTruncated, "data ends inside a marker", size);
  *code = data[pos++];
  return Status::ok();
}

Status JpegMarkers::segment(size_t at, uint32_t* length, size_t* body) {
  if (size - pos < 2) {
    return error(StatusCode::kTruncated, "data ends inside a segment length", size);
  }
  *length = u16(pos);
  if (*length < 2) return error(StatusCode::kParseError, "segment length under 2", at);
  if (*length > size - pos) {
    return error(StatusCode::kTruncated, "data ends inside a marker segment", size);
  }
  *body = pos + 2;
  pos += *length;
  return Status::ok();
}

Status JpegMarkers::frame(size_t at, const char* name, JpegFrameHeader* f) {
  uint32_t length = 0;
  size_t b = 0;
  SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
  if (f->read) return error(StatusCode::kParseError, "a second SOF marker", at);
  if (length < 8) {
    return make_error(StatusCode::kParseError, codec, ": ", name, " segment too short").at_byte(at);
  }
  f->precision = u8(b);
  f->rows = u16(b + 1);
  f->columns = u16(b + 3);
  const uint32_t components = u8(b + 5);
  if (components != 1 || length != 8 + 3 * components) {
    return make_error(StatusCode::kUnsupported, codec, ": ", name, " has ", components,
                      " components (length must be 11): only one is supported, not colour")
        .at_byte(at);
  }
  f->component = u8(b + 6);
  if (f->precision < 2 || f->precision > 16) {
    return make_error(StatusCode::kParseError, codec, ": ", name, " sample precision not in 2..16")
        .at_byte(at);
  }
  f->read = true;
  return Status::ok();
}

Status JpegMarkers::check_frame(size_t at, const char* name, const JpegFrameHeader& f,
                                uint32_t rows, uint32_t columns, uint32_t max_precision) const {
  if (f.rows != rows || f.columns != columns) {
    return make_error(StatusCode::kParseError, codec, ": ", name, " image size ", f.columns, " x ",
                      f.rows, " differs from the DICOM Columns x Rows")
        .at_byte(at);
  }
  if (f.precision > max_precision) {
    return make_error(StatusCode::kParseError, codec, ": ", name, " sample precision ", f.precision,
                      " is over the DICOM Bits Allocated ", max_precision)
        .at_byte(at);
  }
  return Status::ok();
}

}  // namespace ct_detail
}  // namespace splintcore

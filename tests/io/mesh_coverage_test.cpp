// Branches of the PLY and OBJ readers, their shared text scanner and read_mesh's format
// detection (src/io/ply_read.cpp, src/io/obj_read.cpp, src/io/mesh_text.h) that the other
// tests do not reach (issue 9: >= 95% branch coverage of the parsers, measured by
// tools/coverage.sh). Each case asserts the code, the message and the position; failures
// leave the arena where it was. A cap sweep reaches every allocation failure of the readers.
#include <gtest/gtest.h>

#include <charconv>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "io/mesh_text.h"
#include "splintcore/io.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using ReadFn = Status (*)(const Context&, const ByteSource&, const MeshReadOptions&, Mesh*,
                          MeshReadInfo*);

struct Reading {
  Status status;
  MeshReadInfo info;
  size_t vertices = 0;
  size_t triangles = 0;
  std::vector<Vec3> positions;
};

// Reads `bytes` with `fn`; `size` replaces the source's size (kUnknownSize hides it).
Reading run(ReadFn fn, const std::string& bytes, MeshReadOptions options = MeshReadOptions{},
            const char* name = "m", uint64_t size = 0, size_t cap = size_t{1} << 20) {
  test::TestArena t(cap);
  EXPECT_NE(t.arena.allocate(16), nullptr);
  const size_t used = t.arena.used();
  MemorySource ms{reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), 0, 0};
  ByteSource source = memory_source(&ms, name);
  source.name = name;
  if (size != 0) source.size = size;
  Mesh mesh(&t.arena);
  Reading r;
  r.status = fn(Context(&t.arena), source, options, &mesh, &r.info);
  r.vertices = mesh.vertices.size();
  r.triangles = mesh.triangles.size();
  r.positions.assign(mesh.vertices.begin(), mesh.vertices.end());
  if (!r.status.is_ok()) {
    EXPECT_EQ(t.arena.used(), used) << "a failed read left memory in the arena";
    EXPECT_EQ(r.vertices + r.triangles, 0u) << "a failed read left a partial mesh";
  }
  return r;
}

bool has(const Status& s, const char* fragment) {
  return std::strstr(s.message(), fragment) != nullptr;
}

#define EXPECT_ERROR(reading, code_, fragment)                                        \
  do {                                                                                \
    EXPECT_EQ((reading).status.code(), (code_)) << test::format((reading).status);    \
    EXPECT_TRUE(has((reading).status, (fragment))) << test::format((reading).status); \
  } while (0)

const char kPlyHead[] = "ply\nformat ascii 1.0\n";
const char kTriangleBody[] = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
std::string ascii_ply(const std::string& header_lines, const std::string& body) {
  return std::string(kPlyHead) + header_lines + "end_header\n" + body;
}
const char kXyzFace[] =
    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\n";

// ---- the shared scanner (mesh_text.h) -------------------------------------------------------

TEST(MeshTextCoverage, NumbersAndIntegers) {
  double d = 0;
  auto real = [&](const char* text, bool as_float) {
    return meshio::parse_real(text, text + std::strlen(text), as_float, &d);
  };
  EXPECT_EQ(real("", true), StatusCode::kParseError);
  EXPECT_EQ(real("+", true), StatusCode::kParseError);
  EXPECT_EQ(real("+-1", true), StatusCode::kParseError);
  EXPECT_EQ(real("++1", false), StatusCode::kParseError);
  EXPECT_EQ(real("+2.5", true), StatusCode::kOk);
  EXPECT_EQ(d, 2.5);
  EXPECT_EQ(real("1E+2", false), StatusCode::kOk);
  EXPECT_EQ(d, 100.0);
  EXPECT_EQ(real("1e-1", true), StatusCode::kOk);
  EXPECT_EQ(d, static_cast<double>(0.1f));                // rounded to float32
  EXPECT_EQ(real("1-2", true), StatusCode::kParseError);  // stops early
  EXPECT_EQ(real("1-2", false), StatusCode::kParseError);
  EXPECT_EQ(real("e5", false), StatusCode::kParseError);  // no digits
  EXPECT_EQ(real("-inf", true), StatusCode::kNonFinite);
  EXPECT_EQ(real("NaN", false), StatusCode::kNonFinite);
  EXPECT_EQ(real("-x", false), StatusCode::kParseError);
  EXPECT_EQ(real("1e999", false), StatusCode::kParseError);  // out of range
  int64_t i = 0;
  auto integer = [&](const char* text) {
    return meshio::parse_integer(text, text + std::strlen(text), &i);
  };
  EXPECT_TRUE(integer("+5"));
  EXPECT_EQ(i, 5);
  EXPECT_TRUE(integer("-7"));
  EXPECT_EQ(i, -7);
  EXPECT_FALSE(integer("+"));
  EXPECT_FALSE(integer("+-5"));
  EXPECT_FALSE(integer(""));
  EXPECT_FALSE(integer("5x"));
  EXPECT_FALSE(integer("99999999999999999999"));
}

// parse_integer sums short digit runs itself: on random tokens (signs, digits, lengths 0 to 24,
// a stray character) it answers as std::from_chars does on the token (after a leading '+'
// that is not followed by a sign is dropped).
TEST(MeshTextCoverage, ParseIntegerAnswersAsFromChars) {
  std::mt19937 rng(29);
  const char alphabet[] = "0123456789012345678901234567890123456789-+x/ ";
  std::uniform_int_distribution<size_t> length(0, 24), pick(0, sizeof(alphabet) - 2);
  int accepted = 0;
  for (int n = 0; n < 200000; ++n) {
    std::string token(length(rng), '0');
    for (char& c : token) c = alphabet[pick(rng)];
    if (n % 2 == 0 && !token.empty()) {  // half of them digits only, after a sign or not
      for (size_t k = 1; k < token.size(); ++k) token[k] = static_cast<char>('0' + pick(rng) % 10);
    }
    const char* first = token.data();
    const char* last = first + token.size();
    int64_t ours = -1;
    const bool ok = meshio::parse_integer(first, last, &ours);
    const char* from = first;
    if (from != last && *from == '+' && last - from > 1 && from[1] != '-') ++from;
    int64_t theirs = -1;
    const auto r = std::from_chars(from, last, theirs, 10);
    const bool expected = r.ec == std::errc() && r.ptr == last;
    ASSERT_EQ(ok, expected) << "'" << token << "'";
    if (ok) {
      EXPECT_EQ(ours, theirs) << "'" << token << "'";
      ++accepted;
    }
  }
  EXPECT_GT(accepted, 50000);
}

TEST(MeshTextCoverage, ArgumentsAreChecked) {
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  for (ReadFn fn : {&read_obj, &read_ply, &read_mesh}) {
    test::TestArena t(size_t{1} << 20);
    MemorySource ms{reinterpret_cast<const uint8_t*>(obj.data()), obj.size(), 0, 0};
    ByteSource source = memory_source(&ms, "m.obj");
    Mesh mesh(&t.arena);
    ByteSource no_read = source;
    no_read.read = nullptr;
    Status s = fn(Context(&t.arena), no_read, MeshReadOptions{}, &mesh, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_TRUE(has(s, "byte source has no read()")) << s.message();
    if (fn == &read_mesh) continue;  // read_mesh checks the rest in the reader it picks
    s = fn(Context(&t.arena), source, MeshReadOptions{}, nullptr, nullptr);
    EXPECT_TRUE(has(s, "output mesh must be empty")) << s.message();
    ASSERT_TRUE(mesh.vertices.push_back(Vec3{}));
    s = fn(Context(&t.arena), source, MeshReadOptions{}, &mesh, nullptr);
    EXPECT_TRUE(has(s, "output mesh must be empty")) << s.message();
    mesh.vertices.clear();
    ASSERT_TRUE(mesh.triangles.push_back(Triangle{{0, 0, 0}}));
    s = fn(Context(&t.arena), source, MeshReadOptions{}, &mesh, nullptr);
    EXPECT_TRUE(has(s, "output mesh must be empty")) << s.message();
    mesh.triangles.clear();
    MeshReadOptions o;
    o.weld = true;
    o.round_to_float32 = false;
    s = fn(Context(&t.arena), source, o, &mesh, nullptr);
    EXPECT_TRUE(has(s, "weld needs round_to_float32")) << s.message();
    for (size_t bad : {size_t{63}, (size_t{1} << 20) + 1}) {
      MeshReadOptions l;
      l.max_line_bytes = bad;
      s = fn(Context(&t.arena), source, l, &mesh, nullptr);
      EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
      EXPECT_TRUE(has(s, "max_line_bytes must be 64..1048576")) << s.message();
    }
  }
}

TEST(MeshTextCoverage, BlanksLongTokensAndUnnamedSources) {
  // Tabs, CRs inside a line, form feeds and vertical tabs separate tokens.
  Reading r = run(&read_obj, "v\t0\r0\f0\nv 1\v0 0\nv 0 1 0\r\nf 1 2 3\n");
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.triangles, 1u);
  // A bad token longer than 40 characters is cut in the message.
  const std::string long_token(60, 'q');
  r = run(&read_obj, "v 0 0 " + long_token + "\n");
  EXPECT_ERROR(r, StatusCode::kParseError, ("found '" + long_token.substr(0, 40) + "'").c_str());
  EXPECT_FALSE(has(r.status, long_token.substr(0, 41).c_str()));
  EXPECT_EQ(r.status.line(), 1u);
  EXPECT_EQ(r.status.column(), 7u);
  // A source without a name: the error has no file.
  r = run(&read_obj, "v 0 0\n", MeshReadOptions{}, nullptr);
  EXPECT_ERROR(r, StatusCode::kParseError, "a 'v' line needs x, y and z");
  EXPECT_STREQ(r.status.file(), "");
  r = run(&read_obj, "v 0 0\n", MeshReadOptions{}, "named.obj");
  EXPECT_STREQ(r.status.file(), "named.obj");
}

// Every cap from 0 up to what the read needs (in 8-byte steps): each failure is a clean
// kArenaExhausted (arena back, no mesh: checked by run()), and the first success is the mesh.
TEST(MeshTextCoverage, EveryCapFailsCleanlyUntilTheReadFits) {
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
  const std::string ply = ascii_ply(
      "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\n",
      "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  struct Input {
    ReadFn fn;
    const std::string* bytes;
    bool weld;
    uint64_t size;
  };
  const Input inputs[] = {{&read_obj, &obj, false, 0},
                          {&read_obj, &obj, true, 0},
                          {&read_ply, &ply, false, 0},
                          {&read_ply, &ply, true, 0},
                          {&read_ply, &ply, false, kUnknownSize}};
  for (const Input& in : inputs) {
    MeshReadOptions o;
    o.weld = in.weld;
    o.max_line_bytes = 64;
    o.chunk_bytes = 4096;
    size_t failures = 0;
    bool done = false;
    for (size_t cap = 16; cap < (size_t{64} << 10) && !done; cap += 8) {
      Reading r = run(in.fn, *in.bytes, o, "m", in.size, cap);
      if (r.status.is_ok()) {
        EXPECT_EQ(r.triangles, 4u);
        EXPECT_EQ(r.vertices, 4u);
        done = true;
      } else {
        EXPECT_EQ(r.status.code(), StatusCode::kArenaExhausted) << test::format(r.status);
        ++failures;
      }
    }
    EXPECT_TRUE(done);
    EXPECT_GT(failures, 500u);  // the 4096-byte read buffer alone
  }
}

// ---- OBJ ------------------------------------------------------------------------------------

TEST(ObjCoverage, CornersValuesAndLimits) {
  Reading r = run(&read_obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/0 2 3\n");
  EXPECT_ERROR(r, StatusCode::kParseError, "expected a face corner v, v/vt, v//vn or v/vt/vn");
  EXPECT_EQ(r.status.line(), 4u);
  EXPECT_EQ(r.status.column(), 3u);
  // A fourth value (w, or a colour) may be anything finite or not; a bad one is an error.
  r = run(&read_obj, "v 0 0 0 nan\nv 1 0 0 1\nv 0 1 0 inf\nf 1 2 3\n");
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.triangles, 1u);
  r = run(&read_obj, "v 0 0 0 x\n");
  EXPECT_ERROR(r, StatusCode::kParseError, "expected a number, found 'x'");
  EXPECT_EQ(r.status.column(), 9u);
  // A small chunk is raised to 4096; no vertex limit beyond 32-bit ids.
  MeshReadOptions o;
  o.chunk_bytes = 100;
  o.max_vertices = ~uint64_t{0};
  r = run(&read_obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", o);
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.info.bytes, 32u);
}

struct Cancel {
  uint64_t calls = 0;
  static bool report(void* user, const char*, uint64_t, uint64_t) {
    ++static_cast<Cancel*>(user)->calls;
    return false;
  }
};

TEST(ObjCoverage, ProgressEvery65536LinesCanCancel) {
  std::string text;
  for (int i = 0; i < 70000; ++i) text += "#\n";
  test::TestArena t(size_t{1} << 20);
  MemorySource ms{reinterpret_cast<const uint8_t*>(text.data()), text.size(), 0, 0};
  Cancel cancel;
  Progress progress;
  progress.report = &Cancel::report;
  progress.user = &cancel;
  Mesh mesh(&t.arena);
  Status s = read_obj(Context(&t.arena, nullptr, &progress), memory_source(&ms, "c.obj"),
                      MeshReadOptions{}, &mesh, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kCancelled) << test::format(s);
  EXPECT_EQ(cancel.calls, 1u);
  EXPECT_EQ(t.arena.used(), 0u);
}

// ---- read_mesh: detection and the peeked head ----------------------------------------------

TEST(MeshDetectCoverage, FormatNames) {
  EXPECT_STREQ(mesh_format_name(MeshFormat::kStlBinary), "stl-binary");
  EXPECT_STREQ(mesh_format_name(MeshFormat::kStlAscii), "stl-ascii");
  EXPECT_STREQ(mesh_format_name(MeshFormat::kPlyAscii), "ply-ascii");
  EXPECT_STREQ(mesh_format_name(MeshFormat::kPlyBinaryLittleEndian), "ply-binary-le");
  EXPECT_STREQ(mesh_format_name(MeshFormat::kPlyBinaryBigEndian), "ply-binary-be");
  EXPECT_STREQ(mesh_format_name(MeshFormat::kObj), "obj");
  EXPECT_STREQ(mesh_format_name(MeshFormat::kUnknown), "unknown");
}

TEST(MeshDetectCoverage, ContentThenName) {
  auto detect = [](const std::string& head, const char* name = nullptr) {
    return detect_mesh_format(reinterpret_cast<const uint8_t*>(head.data()), head.size(), name);
  };
  EXPECT_EQ(detect("ply\r\nformat ascii 1.0\r\n"), MeshFormat::kPlyAscii);
  EXPECT_EQ(detect("plyx\n"), MeshFormat::kStlBinary);
  EXPECT_EQ(detect("ply"), MeshFormat::kStlBinary);  // too short for "ply\n"
  EXPECT_EQ(detect(" \t\r\nSOLID x\n"), MeshFormat::kStlAscii);
  EXPECT_EQ(detect("solid\tx\r\n"), MeshFormat::kStlAscii);
  EXPECT_EQ(detect("solid x\x7f"), MeshFormat::kStlBinary);  // not printable
  EXPECT_EQ(detect(std::string("solid x\x80", 9)), MeshFormat::kStlBinary);
  EXPECT_EQ(detect("sol"), MeshFormat::kStlBinary);
  EXPECT_EQ(detect("solix"), MeshFormat::kStlBinary);
  EXPECT_EQ(detect(" \t\r\n# a comment\n"), MeshFormat::kObj);
  EXPECT_EQ(detect("\n\r\tv\t1 2 3\n"), MeshFormat::kObj);
  EXPECT_EQ(detect("mtllib\ra.mtl\n"), MeshFormat::kObj);
  EXPECT_EQ(detect("usemtl\nx"), MeshFormat::kObj);
  EXPECT_EQ(detect("vertex 1 2 3\n"), MeshFormat::kStlBinary);           // not an OBJ keyword
  EXPECT_EQ(detect("v"), MeshFormat::kStlBinary);                        // cut off by the window
  EXPECT_EQ(detect(" \n\t"), MeshFormat::kStlBinary);                    // only blanks
  EXPECT_EQ(detect(std::string("v 1\x01", 4)), MeshFormat::kStlBinary);  // control byte
  EXPECT_EQ(detect("v 1\x7f"), MeshFormat::kStlBinary);
  EXPECT_EQ(detect(std::string(4, '\0'), "a.PLY"), MeshFormat::kPlyAscii);
  EXPECT_EQ(detect(std::string(4, '\0'), "a.Obj"), MeshFormat::kObj);
  EXPECT_EQ(detect(std::string(4, '\0'), "y"), MeshFormat::kStlBinary);  // shorter than ".ply"
  EXPECT_EQ(detect(std::string(4, '\0'), "a.stl"), MeshFormat::kStlBinary);
}

// Sources that fail or break the read() contract.
struct BadSource {
  int64_t result = -1;
  static int64_t read(void* user, uint8_t* buffer, size_t capacity) {
    (void)buffer;
    const int64_t r = static_cast<BadSource*>(user)->result;
    return r >= 0 ? static_cast<int64_t>(capacity) + r : r;
  }
};

TEST(MeshDetectCoverage, ReadMeshSourcesAndPaths) {
  test::TestArena t(size_t{4} << 20);
  for (int64_t result : {int64_t{-1}, int64_t{1}}) {
    BadSource bad{result};
    ByteSource source;
    source.read = &BadSource::read;
    source.user = &bad;
    source.name = "bad.stl";
    Mesh mesh(&t.arena);
    Status s = read_mesh(Context(&t.arena), source, MeshReadOptions{}, &mesh, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kIoError) << test::format(s);
    EXPECT_TRUE(has(s, result < 0 ? "read failed" : "returned more than asked")) << s.message();
  }
  // An ASCII STL through read_mesh, longer than the 1024-byte peek.
  std::string stl = "solid t\n";
  while (stl.size() < 2000) {
    stl +=
        " facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
        "   vertex 0 1 0\n  endloop\n endfacet\n";
  }
  stl += "endsolid t\n";
  Reading r = run(&read_mesh, stl);
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.info.format, MeshFormat::kStlAscii);
  EXPECT_EQ(r.vertices, 3u);
  EXPECT_EQ(r.info.bytes, stl.size());
  // An OBJ by its name only (its first statement is not a keyword the peek knows).
  r = run(&read_mesh, "l 1 2\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", MeshReadOptions{}, "x.obj");
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.info.format, MeshFormat::kObj);
}

// ---- PLY header ---------------------------------------------------------------------------

struct PlyCase {
  const char* name;
  std::string text;
  StatusCode code;
  const char* fragment;
  uint64_t line;
};

TEST(PlyCoverage, HeaderErrors) {
  std::string many_elements;
  for (int i = 0; i < 33; ++i) many_elements += "element e" + std::to_string(i) + " 0\n";
  std::string many_properties = "element vertex 0\n";
  for (int i = 0; i < 257; ++i) many_properties += "property float p" + std::to_string(i) + "\n";
  const std::vector<PlyCase> cases = {
      {"text after end_header", "ply\nformat ascii 1.0\nend_header x\n", StatusCode::kParseError,
       "expected nothing after 'end_header', found 'x'", 3},
      {"second format", "ply\nformat ascii 1.0\nformat ascii 1.0\n", StatusCode::kParseError,
       "second 'format' line", 3},
      {"format line too long", "ply\nformat ascii 1.0 x\n", StatusCode::kParseError,
       "expected the end of the format line", 2},
      {"too many elements", ascii_ply(many_elements, ""), StatusCode::kLimitExceeded,
       "more than 32 elements", 35},
      {"second vertex element", ascii_ply("element vertex 0\nelement vertex 0\n", ""),
       StatusCode::kParseError, "second element of this name", 4},
      {"second face element", ascii_ply("element face 0\nelement face 0\n", ""),
       StatusCode::kParseError, "second element of this name", 4},
      {"element line too long", ascii_ply("element vertex 0 x\n", ""), StatusCode::kParseError,
       "expected the end of the element line", 3},
      {"too many properties", ascii_ply(many_properties, ""), StatusCode::kLimitExceeded,
       "more than 256 properties", 260},
      {"property line too long", ascii_ply("element vertex 0\nproperty float x y\n", ""),
       StatusCode::kParseError, "expected the end of the property line", 4},
      {"float list count",
       ascii_ply("element face 0\nproperty list float int vertex_indices\n", ""),
       StatusCode::kUnsupported, "list count type is not an integer", 4},
      {"double list count",
       ascii_ply("element face 0\nproperty list double int vertex_indices\n", ""),
       StatusCode::kUnsupported, "list count type is not an integer", 4},
      {"float indices", ascii_ply("element face 0\nproperty list uchar float vertex_index\n", ""),
       StatusCode::kUnsupported, "vertex indices of a non-integer type", 4},
      {"no format", "ply\nend_header\n", StatusCode::kParseError, "PLY header has no 'format' line",
       2},
      {"no x", ascii_ply("element vertex 0\nproperty float y\nproperty float z\n", ""),
       StatusCode::kParseError, "lacks one of the scalar properties x, y, z", 6},
      {"no y", ascii_ply("element vertex 0\nproperty float x\nproperty float z\n", ""),
       StatusCode::kParseError, "lacks one of the scalar properties x, y, z", 6},
  };
  for (const PlyCase& c : cases) {
    SCOPED_TRACE(c.name);
    Reading r = run(&read_ply, c.text);
    EXPECT_ERROR(r, c.code, c.fragment);
    EXPECT_EQ(r.status.line(), c.line) << test::format(r.status);
  }
}

TEST(PlyCoverage, HeaderOddsThatAreAccepted) {
  // Blank header lines, a long element name (kept to 31 characters in messages), obj_info.
  const std::string long_name(50, 'n');
  const std::string text = std::string("ply\n\nformat ascii 1.0\n   \nobj_info x\n") + "element " +
                           long_name + " 1\nproperty uchar a\n" + kXyzFace + "end_header\n7\n" +
                           kTriangleBody;
  Reading r = run(&read_ply, text);
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.triangles, 1u);
  // The long name in an error: cut to 31 characters.
  r = run(&read_ply, std::string("ply\nformat ascii 1.0\nelement ") + long_name +
                         " 1\nproperty list uchar uchar a\n" + kXyzFace + "end_header\n3 1\n" +
                         kTriangleBody);
  EXPECT_ERROR(
      r, StatusCode::kParseError,
      ("list of 3 items has fewer on the line of " + long_name.substr(0, 31) + " 0").c_str());
  EXPECT_FALSE(has(r.status, long_name.substr(0, 32).c_str()));
  EXPECT_EQ(r.status.line(), 12u);
}

// ---- PLY bodies ---------------------------------------------------------------------------

std::string binary_ply(const std::string& properties, const std::string& body, bool big = false) {
  return std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
         " 1.0\n" + properties + "end_header\n" + body;
}
std::string f32(float f) {
  std::string s(4, '\0');
  std::memcpy(&s[0], &f, 4);
  return s;
}
std::string le(uint64_t v, int bytes) {
  std::string s;
  for (int i = 0; i < bytes; ++i) s += static_cast<char>(i < 8 ? (v >> (8 * i)) & 0xff : 0);
  return s;
}
const char kBinVertices[] =
    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
std::string bin_triangle_vertices() {
  return f32(0) + f32(0) + f32(0) + f32(1) + f32(0) + f32(0) + f32(0) + f32(1) + f32(0);
}

TEST(PlyCoverage, BinaryIntegerTypes) {
  // int8 counts, int16 and int32 indices.
  Reading r =
      run(&read_ply, binary_ply(std::string(kBinVertices) +
                                    "element face 2\nproperty list char short vertex_indices\n"
                                    "element edge 1\nproperty list int8 int junk\n",
                                bin_triangle_vertices() + le(3, 1) + le(0, 2) + le(1, 2) +
                                    le(2, 2) + le(3, 1) + le(2, 2) + le(1, 2) + le(0, 2) +
                                    le(2, 1) + le(5, 4) + le(6, 4)));
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.triangles, 2u);
  r = run(&read_ply,
          binary_ply(std::string(kBinVertices) +
                         "element face 1\nproperty list uint8 int32 vertex_indices\n",
                     bin_triangle_vertices() + le(3, 1) + le(0, 4) + le(1, 4) + le(2, 4)));
  SPLINTCORE_EXPECT_OK(r.status);
  // A negative int8 list count.
  const std::string header =
      std::string(kBinVertices) + "element face 1\nproperty list char int vertex_indices\n";
  r = run(&read_ply, binary_ply(header, bin_triangle_vertices() + le(0xff, 1) + le(0, 12)));
  EXPECT_ERROR(r, StatusCode::kParseError, "face 0 has a list of -1 items");
  EXPECT_EQ(r.status.index(), 0u);
  // Two corners.
  r = run(&read_ply, binary_ply(header, bin_triangle_vertices() + le(2, 1) + le(0, 8) + le(0, 4)));
  EXPECT_ERROR(r, StatusCode::kParseError, "face 0 has 2 vertices; a polygon needs at least 3");
  // A face index with no vertices at all.
  r = run(&read_ply, binary_ply("element vertex 0\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 1\n"
                                "property list uchar int vertex_indices\n",
                                le(3, 1) + le(0, 12)));
  EXPECT_ERROR(r, StatusCode::kParseError, "face 0 has vertex index 0, outside 0..0 (0 vertices)");
}

TEST(PlyCoverage, AsciiValuesAndLines) {
  // A blank line between records and at the end; float32 coordinates read as float32 even
  // without rounding, doubles kept.
  MeshReadOptions exact;
  exact.round_to_float32 = false;
  Reading r = run(&read_ply,
                  ascii_ply("element vertex 3\nproperty float x\nproperty double y\n"
                            "property float z\nelement face 1\n"
                            "property list uchar int vertex_indices\n",
                            "0.1 0.1 0\n\n1 0 0\n0 1 0\n3 0 1 2\n\n  \n"),
                  exact);
  SPLINTCORE_EXPECT_OK(r.status);
  ASSERT_EQ(r.positions.size(), 3u);
  EXPECT_EQ(r.positions[0].x, static_cast<double>(0.1f));
  EXPECT_EQ(r.positions[0].y, 0.1);
  // Integer values out of their type, or not integers.
  const std::string xyz =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  r = run(&read_ply, ascii_ply(xyz + "element face 1\nproperty list uchar int vertex_indices\n",
                               "0 0 0\n1 0 0\n0 1 0\n-1 0 1 2\n"));
  EXPECT_ERROR(r, StatusCode::kParseError, "expected an integer of the declared type, found '-1'");
  EXPECT_EQ(r.status.line(), 13u);
  EXPECT_EQ(r.status.column(), 1u);
  r = run(&read_ply, ascii_ply(xyz + "element face 1\nproperty list uchar int vertex_indices\n",
                               "0 0 0\n1 0 0\n0 1 0\nthree 0 1 2\n"));
  EXPECT_ERROR(r, StatusCode::kParseError, "found 'three'");
  // More values than declared.
  r = run(&read_ply, ascii_ply(xyz, "0 0 0 9\n1 0 0\n0 1 0\n"));
  EXPECT_ERROR(r, StatusCode::kParseError, "more values than the element declares, found '9'");
  EXPECT_EQ(r.status.line(), 8u);
  EXPECT_EQ(r.status.column(), 7u);
}

TEST(PlyCoverage, SizesAgainstTheSource) {
  const std::string text = ascii_ply(kXyzFace, kTriangleBody);
  // A small chunk is raised to 4096; no vertex limit beyond 32-bit ids.
  MeshReadOptions o;
  o.chunk_bytes = 10;
  o.max_vertices = ~uint64_t{0};
  Reading r = run(&read_ply, text, o);
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.info.bytes, text.size());
  // A source claiming fewer bytes than the header has.
  r = run(&read_ply, text, MeshReadOptions{}, "m", 10);
  EXPECT_ERROR(r, StatusCode::kTruncated, "but 0 follow the header");
  EXPECT_EQ(r.status.byte_offset(), 10u);
  // Counts whose bytes overflow 64 bits: in a multiplication, in the sum; size known or not.
  const std::string huge =
      "element junk 9000000000000000000\nproperty uchar a\nproperty uchar b\nproperty uchar c\n";
  const std::string sum =
      "element a 9000000000000000000\nproperty uchar p\n"
      "element b 9000000000000000000\nproperty uchar p\n"
      "element c 9000000000000000000\nproperty uchar p\n";
  for (const std::string* extra : {&huge, &sum}) {
    const std::string big = ascii_ply(*extra + kXyzFace, kTriangleBody);
    r = run(&read_ply, big);
    EXPECT_ERROR(r, StatusCode::kTruncated, "needing at least 2^64 bytes of data but");
    EXPECT_EQ(r.status.byte_offset(), big.size());
    r = run(&read_ply, big, MeshReadOptions{}, "m", kUnknownSize);
    EXPECT_ERROR(r, StatusCode::kTruncated, "needing at least 2^64 bytes of data");
    EXPECT_FALSE(has(r.status, "follow the header"));
    EXPECT_EQ(r.status.byte_offset(), big.size() - std::strlen(kTriangleBody));
  }
}

}  // namespace
}  // namespace splintcore

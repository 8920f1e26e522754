#include "files.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstring>
#include <memory>

namespace splintcore {
namespace tool {

BackgroundHasher::BackgroundHasher(Sha256* sha) : sha_(sha) {
  for (std::vector<uint8_t>& slot : slot_) slot.reserve(kSlotBytes);
  thread_ = std::thread([this] { run(); });
}

BackgroundHasher::~BackgroundHasher() { finish(); }

void BackgroundHasher::add(const uint8_t* data, size_t bytes) {
  while (bytes > 0) {
    std::vector<uint8_t>& slot = slot_[fill_];
    const size_t n = std::min(bytes, kSlotBytes - slot.size());
    slot.insert(slot.end(), data, data + n);
    data += n;
    bytes -= n;
    if (slot.size() == kSlotBytes) publish();
  }
}

void BackgroundHasher::publish() {
  std::unique_lock<std::mutex> lock(mutex_);
  ++ready_;
  changed_.notify_all();
  changed_.wait(lock, [this] { return ready_ < kSlots; });  // the next slot is free
  fill_ = (fill_ + 1) % kSlots;
}

void BackgroundHasher::finish() {
  if (!thread_.joinable()) return;
  if (!slot_[fill_].empty()) publish();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finishing_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void BackgroundHasher::run() {
  size_t next = 0;  // the oldest published slot
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return ready_ > 0 || finishing_; });
      if (ready_ == 0) return;  // finishing, all hashed
    }
    std::vector<uint8_t>& slot = slot_[next];
    sha_->update(slot.data(), slot.size());
    slot.clear();
    next = (next + 1) % kSlots;
    std::lock_guard<std::mutex> lock(mutex_);
    --ready_;
    changed_.notify_all();
  }
}

Status InputFile::open(const char* path, uint64_t max_bytes) {
  path_ = path;
  max_bytes_ = max_bytes;
  count_ = 0;
  over_limit_ = false;
  if (std::strcmp(path, "-") == 0) {
    // Standard input can be read once: a second "-" would find it at its end.
    static std::atomic<bool> taken{false};
    if (taken.exchange(true)) {
      return make_error(StatusCode::kInvalidArgument,
                        "standard input (\"-\") given for more than one input");
    }
    SPLINTCORE_RETURN_IF_ERROR(file_.open_standard_input());
    path_ = FileSource::kStandardInputName;
  } else {
    SPLINTCORE_RETURN_IF_ERROR(file_.open(path));
  }
  inner_ = file_.source();
  if (inner_.size != kUnknownSize && inner_.size > max_bytes) {
    file_.close();
    return limit_status(inner_.size);
  }
  return Status::ok();
}

Status InputFile::limit_status(uint64_t size) const {
  Status s = size != kUnknownSize
                 ? make_error(StatusCode::kLimitExceeded, "file is ", size, " bytes,")
                 : make_error(StatusCode::kLimitExceeded, "file is");
  return s.append(" over the limit of ")
      .append_u64(max_bytes_)
      .append(" bytes (--max-input-bytes raises it)")
      .in_file(path_.c_str());
}

int64_t InputFile::read(void* user, uint8_t* buffer, size_t capacity) {
  InputFile* self = static_cast<InputFile*>(user);
  const int64_t n = self->inner_.read(self->inner_.user, buffer, capacity);
  if (n <= 0) return n;
  if (static_cast<uint64_t>(n) > self->max_bytes_ - self->count_) {  // count_ <= max_bytes_
    self->over_limit_ = true;
    return -1;
  }
  self->count_ += static_cast<uint64_t>(n);
  if (self->sha_ != nullptr) self->sha_->update(buffer, static_cast<size_t>(n));
  if (self->hasher_ != nullptr) self->hasher_->add(buffer, static_cast<size_t>(n));
  return n;
}

ByteSource InputFile::source() {
  ByteSource s = inner_;
  s.read = &InputFile::read;
  s.user = this;
  return s;
}

Status InputFile::read_all(std::vector<uint8_t>* out) {
  out->clear();
  if (inner_.size != kUnknownSize) out->reserve(static_cast<size_t>(inner_.size));
  std::vector<uint8_t> buffer(size_t{1} << 16);
  int64_t n = 0;
  while ((n = read(this, buffer.data(), buffer.size())) > 0) {
    out->insert(out->end(), buffer.data(), buffer.data() + n);
  }
  if (n < 0) {
    out->clear();
    if (over_limit_) return limit_status(kUnknownSize);
    return make_error(StatusCode::kIoError, "read failed").in_file(path_.c_str());
  }
  return Status::ok();
}

Status InputFile::read_rest() {
  uint8_t buffer[4096];
  int64_t n = 0;
  while ((n = read(this, buffer, sizeof(buffer))) > 0) {
  }
  if (n == 0) return Status::ok();
  if (over_limit_) return limit_status(kUnknownSize);
  return make_error(StatusCode::kIoError, "read failed").in_file(path_.c_str());
}

Status read_mesh_file(const Context& ctx, const char* path, uint64_t max_bytes, bool hash,
                      Mesh* mesh, MeshFileInfo* info, const Aabb& keep) {
  InputFile file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path, max_bytes));
  Sha256 sha;
  // With more than one thread the file is hashed beside the reading (the same digest).
  const bool beside = hash && has_threads(ctx.executor);
  std::unique_ptr<BackgroundHasher> hasher;
  if (beside) {
    hasher.reset(new BackgroundHasher(&sha));
    file.hash_into(hasher.get());
  } else if (hash) {
    file.hash_into(&sha);
  }
  MeshReadOptions options;
  options.weld = true;
  options.keep = keep;
  MeshReadInfo read;
  Status s = read_mesh(ctx, file.source(), options, mesh, &read);
  if (s.is_ok() && hash) s = file.read_rest();
  if (hasher != nullptr) hasher->finish();
  if (file.went_over_limit()) return file.limit_status(kUnknownSize);
  SPLINTCORE_RETURN_IF_ERROR(s);
  if (info != nullptr) {
    info->format = read.format;
    info->triangles = read.triangles;
    info->bytes = read.bytes;
    if (hash) {
      uint8_t digest[32];
      sha.finish(digest);
      char hex[65];
      Sha256::to_hex(digest, hex);
      info->sha256 = hex;
    }
  }
  return Status::ok();
}

Status read_mesh_files(const Context& ctx, const std::vector<const char*>& paths,
                       uint64_t max_bytes, bool hash, std::vector<Mesh>* out,
                       std::vector<MeshFileInfo>* infos) {
  out->clear();
  out->resize(paths.size());
  for (Mesh& m : *out) m.bind(ctx.arena);
  if (infos != nullptr) {
    infos->clear();
    infos->resize(paths.size());
  }
  for (size_t i = 0; i < paths.size(); ++i) {
    SPLINTCORE_RETURN_IF_ERROR(read_mesh_file(ctx, paths[i], max_bytes, hash, &(*out)[i],
                                              infos != nullptr ? &(*infos)[i] : nullptr));
  }
  return Status::ok();
}

Status read_whole_input(const char* path, uint64_t max_bytes, std::vector<uint8_t>* out) {
  out->clear();
  InputFile file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path, max_bytes));
  return file.read_all(out);
}

const char* encoding_name(MeshFormat format) {
  const bool text = format == MeshFormat::kStlAscii || format == MeshFormat::kPlyAscii ||
                    format == MeshFormat::kObj;
  return text ? "ascii" : "binary";
}

constexpr size_t kTaskWriteBuffer = size_t{1} << 20;

namespace {

// The extension of `path`'s last component, lower case ("" when it has none).
std::string extension_of(const char* path) {
  const char* name = std::strrchr(path, '/');
  name = name != nullptr ? name + 1 : path;
  const char* dot = std::strrchr(name, '.');
  std::string ext = dot != nullptr ? dot + 1 : "";
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return ext;
}

// The output is binary PLY (its name ends in .ply, any case), else STL.
bool writes_ply(const char* path) { return extension_of(path) == "ply"; }

// The streaming writer's options: with threads, a buffer large enough for the records to be
// encoded in tasks (add_mesh), where the arena has room to spare for it.
StlWriteOptions stl_options(const Context& ctx, bool ascii) {
  StlWriteOptions wo;
  wo.format = ascii ? StlFormat::kAscii : StlFormat::kBinary;
  const Arena& arena = *ctx.arena;
  if (has_threads(ctx.executor) && arena.cap() - arena.used() >= kTaskWriteBuffer * 4) {
    wo.buffer_bytes = kTaskWriteBuffer;
  }
  return wo;
}

}  // namespace

const char* mesh_output_format(const char* path, bool ascii) {
  if (writes_ply(path)) return "binary PLY";
  return ascii ? "ascii STL" : "binary STL";
}

Status check_mesh_output(const char* path, bool ascii, bool stl_only) {
  if (writes_ply(path) && stl_only) {
    return make_error(StatusCode::kUnsupported,
                      "this output is streamed as STL: name it .stl (convert makes a PLY of it)")
        .in_file(path);
  }
  if (writes_ply(path) && ascii) {
    return make_error(StatusCode::kUnsupported,
                      "PLY is written binary only: drop --ascii, or name the output .stl")
        .in_file(path);
  }
  // Formats other programs read by name: STL bytes under such a name would not open there.
  const std::string ext = extension_of(path);
  static const char* const kOther[] = {"obj",  "3mf", "off", "amf",  "wrl", "vrml", "x3d", "glb",
                                       "gltf", "dae", "fbx", "step", "stp", "iges", "igs"};
  for (const char* other : kOther) {
    if (ext == other) {
      return make_error(StatusCode::kUnsupported, "cannot write a mesh as .", other,
                        ": splintcore writes meshes as STL (.stl, or any other name) or binary "
                        "PLY (.ply)")
          .in_file(path);
    }
  }
  return Status::ok();
}

Status write_mesh_uncommitted(const Context& ctx, const Mesh& mesh, const char* path, bool ascii,
                              AtomicFile* file) {
  SPLINTCORE_RETURN_IF_ERROR(check_mesh_output(path, ascii));
  SPLINTCORE_RETURN_IF_ERROR(file->open(path));
  const Status s = file->with_write_cause(
      writes_ply(path) ? write_ply(mesh, Span<const uint8_t>(), file->sink())
                       : write_stl(ctx, mesh, file->sink(), stl_options(ctx, ascii)));
  if (!s.is_ok()) file->abort();
  return s;
}

Status write_mesh_atomically(const Context& ctx, const Mesh& mesh, const char* path, bool ascii,
                             cli::OutputSet* outputs) {
  auto file = std::make_unique<AtomicFile>();
  SPLINTCORE_RETURN_IF_ERROR(write_mesh_uncommitted(ctx, mesh, path, ascii, file.get()));
  return cli::OutputSet::place(std::move(file), outputs);
}

Status write_hashed_atomically(const std::string& path,
                               const std::function<Status(const ByteSink&)>& write,
                               std::string* sha256, cli::OutputSet* outputs) {
  auto file = std::make_unique<AtomicFile>();
  SPLINTCORE_RETURN_IF_ERROR(file->open(path.c_str()));
  HashSink h;  // hashes what it passes on to the file
  h.next = file->sink();
  SPLINTCORE_RETURN_IF_ERROR(
      file->with_write_cause(write(hash_sink(&h))));  // ~AtomicFile cleans up
  SPLINTCORE_RETURN_IF_ERROR(cli::OutputSet::place(std::move(file), outputs));
  uint8_t digest[32];
  h.sha.finish(digest);
  char hex[65];
  Sha256::to_hex(digest, hex);
  *sha256 = hex;
  return Status::ok();
}

}  // namespace tool
}  // namespace splintcore

// The chunk window over a ByteSource (private to src/io, and to src/ct, which reads its
// headers and voxels through it): the mesh readers, and the CT readers' ct_detail::Reader
// (lines, skips, a larger buffer) built on it.
#ifndef SPLINTCORE_SRC_IO_READER_H
#define SPLINTCORE_SRC_IO_READER_H

#include <cstring>

#include "splintcore/io.h"

namespace splintcore {
namespace meshio {

// A window over the source: buf[pos, end) holds unread bytes, `base` is the absolute offset
// of buf[0]. The buffer is the caller's.
struct Reader {
  const ByteSource* source = nullptr;
  uint8_t* buf = nullptr;
  size_t cap = 0;
  size_t pos = 0;
  size_t end = 0;
  uint64_t base = 0;
  bool at_eof = false;

  uint64_t offset() const { return base + pos; }
  size_t available() const { return end - pos; }

  // Makes at least `n` (<= cap) bytes available unless the source ends first.
  Status fill(size_t n) {
    SPLINTCORE_ASSERT(n <= cap);
    if (available() >= n || at_eof) return Status::ok();
    if (pos > 0) {
      std::memmove(buf, buf + pos, end - pos);
      base += pos;
      end -= pos;
      pos = 0;
    }
    while (end < n && !at_eof) {
      int64_t got = source->read(source->user, buf + end, cap - end);
      if (got < 0) return make_error(StatusCode::kIoError, "read failed").at_byte(base + end);
      if (static_cast<uint64_t>(got) > cap - end) {
        return Status::error(StatusCode::kIoError, "byte source returned more than asked");
      }
      if (got == 0) at_eof = true;
      end += static_cast<size_t>(got);
    }
    return Status::ok();
  }
};

}  // namespace meshio
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_IO_READER_H

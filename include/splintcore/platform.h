// splintcore platform: the hosted layer (files, atomic output, threads, clock). Everything else
// takes byte sources, sinks and executors; a firmware build leaves this out (CMake option
// SPLINTCORE_WITH_PLATFORM=OFF).
#ifndef SPLINTCORE_PLATFORM_H
#define SPLINTCORE_PLATFORM_H

#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>

#include "splintcore/core.h"
#include "splintcore/io.h"

namespace splintcore {

// A file opened for reading as a ByteSource: a regular file's size from the file system; a
// pipe, a device, or a regular file that reports size 0 but has bytes (procfs, sysfs) as a
// stream of unknown size (kUnknownSize), whose readers count as they go.
class FileSource {
 public:
  FileSource() = default;
  ~FileSource();
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;

  Status open(const char* path);
  // The process's standard input (a pipe, a terminal or a redirected file), named
  // kStandardInputName in messages; close() leaves stdin open.
  Status open_standard_input();
  ByteSource source();
  void close();

  static constexpr const char* kStandardInputName = "(standard input)";

 private:
  Status opened(const char* path);  // the size and the name, file_ being open

  std::FILE* file_ = nullptr;
  bool owned_ = false;  // file_ is closed by close()
  uint64_t size_ = kUnknownSize;
  char path_[Status::kFileCapacity] = {};
};

// Output written atomically: bytes go to a temporary file in the destination's folder; commit()
// flushes, syncs and renames it over the destination. Anything else (an error, a destructor
// without commit) removes the temporary file, so a failed run never leaves an output behind.
// A destination that exists and is neither a regular file nor a folder (/dev/null,
// /dev/stdout, a FIFO) is written in place instead, as a stream: renaming over it would
// replace the device or the pipe itself. A symbolic link to a regular file has that file
// replaced (its temporary file beside it), the link left as it is.
// On Linux the disk writes start while the rest is being written: each MiB written is handed
// to the kernel's writeback (sync_file_range, SYNC_FILE_RANGE_WRITE: it starts the writes and
// waits for none), so commit()'s fsync waits for the last of them, not all. Measured on the
// project's VM (ext4), for the real dentition's 6.7 MB result: fsync 7.6-9.4 ms after a plain
// write, 5.7-7.1 ms with the writeback started as it goes (12 runs); the boolean command at
// --threads 2, whole process, 16 alternated rounds: median 162.5 -> 158.3 ms.
class AtomicFile {
 public:
  AtomicFile() = default;
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  Status open(const char* path);
  ByteSink sink();  // seekable
  // Optional, once everything is written: flushes, and starts the fsync on a thread of its
  // own, so that the wait for the disk overlaps what the caller does next (the boolean command
  // checks its result meanwhile: median 154.8 -> 150.8 ms for the real dentition at --threads
  // 2, whole process, 16 alternated rounds). commit() waits for it; so do abort() and the
  // destructor. Nothing may be written after it.
  Status sync_in_background();
  // Optional: flushes, syncs (or waits for sync_in_background's fsync) and closes the
  // temporary file, which stays where it is until commit() or abort(); on an error it is
  // removed. For outputs placed together: each finished as it is written, then all renamed.
  Status finish();
  // Renames the temporary file over the destination (finishing it first, if not yet).
  Status commit();
  void abort();
  // `s` with the cause of this file's first failed write or seek appended, in the system's
  // words ("write failed: No space left on device", "...: File too large"), when one failed and
  // `s` is an I/O error (what a writer returns when its sink refuses bytes); else `s`.
  Status with_write_cause(Status s) const;
  const char* destination() const { return path_; }  // the path given to open()

 private:
  static bool write(void* self, const uint8_t* data, size_t bytes);
  static bool seek(void* self, uint64_t offset);
  bool write_failed();  // keeps errno (the first failure's); false

  std::FILE* file_ = nullptr;
  std::thread syncer_;    // sync_in_background()'s fsync, when started
  int sync_errno_ = 0;    // its errno (0: synced), read once it is joined
  uint64_t started_ = 0;  // the bytes before this have had their writeback started
  char path_[4096] = {};
  char temp_path_[4096 + 32] = {};
  int slot_ = -1;        // where temp_path_ is registered for the signal handler (-1: nowhere)
  int write_errno_ = 0;  // errno of the first failed write (0: none)
  bool direct_ = false;  // written in place: a device or a pipe (open())
};

// For a program's main(), once, before any output is opened: a run stopped by a signal leaves
// no temporary output file behind. SIGINT, SIGTERM, SIGHUP and SIGPIPE first remove the
// temporary file of every AtomicFile still open (the first 64 open at once; unlink, which a
// signal handler may call), then end the process by the same signal with its default action,
// as if nothing had been installed. SIGXFSZ is ignored, so that a write past the file size
// limit (`ulimit -f`) fails as a write to a full disk does ("cannot write output file: File
// too large", the temporary file removed) instead of killing the process with the file half
// written. A signal ignored when this is called stays ignored (nohup, background jobs). The
// library never calls this itself: an embedding program owns its signals.
void remove_temporary_outputs_on_signals();

// Reads a whole file into arena memory (for tools and tests).
Status read_file(Arena& arena, const char* path, uint64_t max_bytes, Span<uint8_t>* out);

// A pool of std::threads implementing Executor (at most kMaxThreads). Workers take task
// indices from a shared counter; which thread runs which index never affects results, since
// tasks write only to their own slots. threads == 1 runs tasks inline on the caller.
class ThreadExecutor {
 public:
  static constexpr unsigned kMaxThreads = 64;
  explicit ThreadExecutor(unsigned threads);
  ~ThreadExecutor();
  ThreadExecutor(const ThreadExecutor&) = delete;
  ThreadExecutor& operator=(const ThreadExecutor&) = delete;

  const Executor& executor() const { return executor_; }
  unsigned threads() const { return threads_; }

 private:
  static void run(void* self, uint32_t count, TaskFunction task, void* context);
  void worker_loop();
  void drain();

  unsigned threads_ = 1;
  Executor executor_{};
  std::thread workers_[kMaxThreads];
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  uint64_t generation_ = 0;
  bool stopping_ = false;
  TaskFunction task_ = nullptr;
  void* context_ = nullptr;
  uint32_t count_ = 0;
  std::atomic<uint32_t> next_{0};
  uint32_t finished_workers_ = 0;
  std::mutex run_mutex_;  // one run() at a time
};

// Seconds from a monotonic clock (for timing; never reaches output bytes).
double monotonic_seconds();

// Memory for a tool's arena: at least `bytes`, aligned to 2 MiB, in the kernel's ordinary
// pages (not advised for transparent huge pages: on a VM that hands free memory back to its
// host, a huge page's first touch waits for the host to zero 2 MiB, and a run started after a
// second idle spent 0.1-0.2 s more in the kernel; see memory.cpp). nullptr when the system has
// no such memory. Give it back with release_arena_memory(), with the same `bytes`.
void* acquire_arena_memory(uint64_t bytes);
void release_arena_memory(void* p, uint64_t bytes);

// A touch hook (core.h) for an arena over that memory: each stretch the arena is about to use
// for the first time is prefaulted (madvise MADV_POPULATE_WRITE, Linux 5.14 on; elsewhere, or
// when it fails, the pages fault in as they are written, as without the hook). Measured on
// the project's 2-core VM (perf stat -r 15, alternated): `check` of the 543k phantom maxilla
// 6,980 page faults and 0.172-0.177 s without it, 129 and 0.120-0.125 s with it; a fault here
// costs about 5 us, mostly the guest's exception entry and exit, and zeroing the page about
// 0.4 us.
TouchHook arena_prefault_hook();

// A touch hook that touches the arena's memory ahead of its use on a thread of its own, for a
// tool run with two threads or more (where the second core waits through the serial stages:
// reading the files, most of the Boolean). On the project's VM the first access to a 4 KiB
// page costs about 4.7 us even after it is prefaulted (the host maps it then: no fault in the
// guest, perf stat), so a run's first touch of its peak arena is about 1.4 ms a MiB on the
// thread that makes it, and two threads take half the time (a /tmp harness: 24 MiB in 33 ms
// on one, 18 ms on two). The thread prefaults each MiB (as arena_prefault_hook does) and reads
// a byte of each page, keeping `ahead` bytes beyond the furthest point the arena has reached
// (from the start: `ahead` bytes). The arena waits only where the thread is behind, and
// only memory the thread has finished with is handed out: the two never share a byte at
// the same time. Nothing the arena hands out changes (its bytes are the kernel's zeros
// either way). hook()'s step is the thread's chunk, 256 KiB: the arena's first allocation
// waits for that much to be touched, not for the 4 MiB of TouchHook's default step (measured
// on the real dentition at --threads 2, from the run's start to its first read: 6.0 ms with
// 4 MiB, 1.8 ms with 1 MiB, 0.5-1.0 ms with 256 KiB). The thread stops when the toucher is
// destroyed (before the memory is given back). An arena over more than `bytes` uses the rest as it
// is. With `bytes` 0 there is no thread and hook() is arena_prefault_hook().
class ArenaToucher {
 public:
  ArenaToucher(void* buffer, size_t bytes, size_t ahead);
  ~ArenaToucher();
  ArenaToucher(const ArenaToucher&) = delete;
  ArenaToucher& operator=(const ArenaToucher&) = delete;

  TouchHook hook();

 private:
  static void touch(void* self, void* begin, size_t bytes);
  void loop();

  unsigned char* buffer_ = nullptr;
  size_t bytes_ = 0;
  size_t ahead_ = 0;
  std::mutex mutex_;
  std::condition_variable more_;  // the target moved, or stop
  std::condition_variable done_;  // done_bytes_ moved
  size_t target_ = 0;             // touch up to here
  size_t done_bytes_ = 0;         // touched up to here
  bool stopping_ = false;
  std::thread thread_;  // (last: started once the rest is set)
};

}  // namespace splintcore

#endif  // SPLINTCORE_PLATFORM_H

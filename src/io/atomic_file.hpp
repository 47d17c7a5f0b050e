// Text files written whole or not at all: a temporary file beside the target, then a rename, so an
// interrupted or failed write never leaves half a file in place of a good one.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace trubal {

// Writes `text` to `path` through a temporary (TemporaryFile) and a rename (no fsync: for outputs,
// not saves; SAVE syncs, io/save.cpp). Throws std::runtime_error naming the file; the temporary is
// removed.
void write_file_atomically(const std::string& path, const std::string& text);
// The same, the text written by `write` straight into the temporary (a table of millions of rows
// is never held in memory whole); what `write` throws removes the temporary and goes on.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// Throws std::runtime_error unless `path` is absent or a regular file: a write through a temporary
// and a rename would replace a symbolic link or a device node with a regular file. With
// `devices` a character device (/dev/null, /dev/full) passes too: for files written in place
// (HIST's). A FIFO never passes: opening one blocks until something reads it.
void check_replaceable(const std::string& path, bool devices = false);

// A temporary file beside `target` that is ours alone: TARGET.tmp-PID-XXXXXX (XXXXXX random),
// created exclusively and never through a link (O_CREAT | O_EXCL | O_NOFOLLOW), so a file or link
// planted under a name we might choose is never opened. It is removed by the destructor unless
// renamed over the target, and by SIGTERM or SIGHUP (which then end the program as they would
// have). Making one first removes the stale temporaries of the same target that killed runs left
// (remove_stale_temporaries).
class TemporaryFile {
 public:
  explicit TemporaryFile(const std::string& target);   // throws "cannot write 'TARGET': ..."
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  // Closes the descriptor (the caller's writes are done); false with errno set when close failed.
  bool close();
  // Hands the descriptor over (to an FdOutput, which closes it); the file stays ours to remove.
  int release() { const int fd = fd_; fd_ = -1; return fd; }
  // Renames the temporary over the target; throws naming the target (the temporary removed).
  void rename_over_target(const std::string& note = "");

 private:
  std::string target_, path_;
  int fd_ = -1, slot_ = -1;
};

// Removes the temporaries of `target` (TARGET.tmp-PID and TARGET.tmp-PID-XXXXXX, in its folder)
// whose process is gone: what a kill -9 during a write leaves.
void remove_stale_temporaries(const std::string& target);

}  // namespace trubal

#include "interp/output.hpp"
#include "support/comm.hpp"

#include <fcntl.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace trubal {

namespace {
int error_now() { return errno ? errno : EIO; }
}  // namespace

int TeeBuffer::overflow(int c) {
  if (c == traits_type::eof()) return traits_type::not_eof(c);
  if (copy_ && copy_->sputc(static_cast<char>(c)) == traits_type::eof() && !copy_error_) copy_error_ = error_now();
  const int r = primary_->sputc(static_cast<char>(c));
  if (r == traits_type::eof() && !primary_error_) primary_error_ = error_now();
  return r;
}

std::streamsize TeeBuffer::xsputn(const char* s, std::streamsize n) {
  if (copy_ && copy_->sputn(s, n) < n && !copy_error_) copy_error_ = error_now();
  const std::streamsize r = primary_->sputn(s, n);
  if (r < n && !primary_error_) primary_error_ = error_now();
  return r;
}

int TeeBuffer::sync() {
  if (copy_ && copy_->pubsync() == -1 && !copy_error_) copy_error_ = error_now();
  const int r = primary_->pubsync();
  if (r == -1 && !primary_error_) primary_error_ = error_now();
  return r;
}

std::string Output::take_log_failure() {
  if (!log_) return "";
  out_.flush();
  err_.flush();
  const int err = out_buf_.copy_error() ? out_buf_.copy_error() : err_buf_.copy_error();
  if (!err) return "";
  const std::string path = log_path_;
  set_log("");
  const std::string failure =
      "the log file '" + path + "' could not be written (" + std::strerror(err) + "); logging stopped";
  if (log_failure_.empty()) log_failure_ = failure;
  return failure;
}

int Output::screen_error() {
  out_.flush();
  err_.flush();
  return out_buf_.primary_error() ? out_buf_.primary_error() : err_buf_.primary_error();
}

Output::Output(std::ostream& out, std::ostream& err)
    : out_buf_(out.rdbuf()), err_buf_(err.rdbuf()), out_(&out_buf_), err_(&err_buf_) {}

void Output::set_log(const std::string& path) {
  out_.flush();
  err_.flush();
  out_buf_.set_copy(nullptr);
  err_buf_.set_copy(nullptr);
  log_.reset();
  log_path_.clear();
  if (path.empty()) return;
  log_path_ = path;
  if (!comm::root()) return;   // rank 0 alone prints, and logs
  // Not through a symbolic link to a file (or to nothing), as no output of ours is: one planted at
  // the name would send the log into another file. The system's own links (/dev/stderr, /proc/self/
  // fd/N) and a link to a device or a pipe are followed.
  struct stat link {}, target {};
  const bool system_name = path.rfind("/dev/", 0) == 0 || path.rfind("/proc/", 0) == 0;
  if (!system_name && ::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode) &&
      !(::stat(path.c_str(), &target) == 0 && (S_ISCHR(target.st_mode) || S_ISFIFO(target.st_mode)))) {
    log_path_.clear();
    throw std::runtime_error("will not append to the log file '" + path +
                             "': it is a symbolic link (name a regular file, or a new one)");
  }
  // Opened without waiting: a FIFO with no reader fails at once (ENXIO) where a plain open would
  // block for ever; then the writes wait as they would for the screen.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_NONBLOCK | O_CLOEXEC, 0666);
  if (fd < 0) {
    const int err = errno;
    log_path_.clear();
    if (err == ENXIO)
      throw std::runtime_error("cannot open the log file '" + path +
                               "': it is a FIFO (a named pipe) that no process reads; writing to it would wait for ever");
    throw std::runtime_error("cannot open the log file '" + path + "' for writing (" + std::strerror(err) + ")");
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  auto file = std::make_unique<FdOutput>(fd);
  log_ = std::move(file);
  log_path_ = path;
  out_buf_.set_copy(log_.get());
  err_buf_.set_copy(log_.get());
}

}  // namespace trubal

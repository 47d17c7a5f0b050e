// An output stream buffer over a file descriptor it owns: for files opened with flags an ofstream
// cannot give (O_EXCL and O_NOFOLLOW for temporaries, O_NONBLOCK to open a FIFO without waiting).
#pragma once

#include <unistd.h>

#include <cerrno>
#include <streambuf>
#include <vector>

namespace trubal {

class FdOutput : public std::streambuf {
 public:
  explicit FdOutput(int fd) : fd_(fd), buffer_(1 << 16) { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
  ~FdOutput() override { close(); }
  FdOutput(const FdOutput&) = delete;
  FdOutput& operator=(const FdOutput&) = delete;
  int fd() const { return fd_; }
  // The errno of the first failed write (0: none).
  int error() const { return error_; }
  // Flushes and closes; false (error() says why) when a write or the close failed.
  bool close() {
    if (fd_ < 0) return error_ == 0;
    flush();
    if (::close(fd_) != 0 && !error_) error_ = errno ? errno : EIO;
    fd_ = -1;
    return error_ == 0;
  }

 protected:
  int overflow(int c) override {
    if (!flush()) return traits_type::eof();
    if (c != traits_type::eof()) {
      *pptr() = static_cast<char>(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return flush() ? 0 : -1; }

 private:
  bool flush() {
    const char* p = pbase();
    while (p < pptr() && fd_ >= 0 && !error_) {
      const ssize_t n = ::write(fd_, p, static_cast<std::size_t>(pptr() - p));
      if (n < 0) {
        if (errno == EINTR) continue;
        error_ = errno ? errno : EIO;
      } else {
        p += n;
      }
    }
    setp(buffer_.data(), buffer_.data() + buffer_.size());
    return error_ == 0 && fd_ >= 0;
  }

  int fd_;
  std::vector<char> buffer_;
  int error_ = 0;
};

}  // namespace trubal

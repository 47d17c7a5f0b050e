#include "io/atomic_file.hpp"
#include "support/comm.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

namespace trubal {

void check_replaceable(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return;   // absent (or unreadable: the write will say)
  if (S_ISREG(st.st_mode)) return;
  const char* what = S_ISLNK(st.st_mode) ? "a symbolic link" : S_ISDIR(st.st_mode) ? "a directory" : "not a regular file";
  throw std::runtime_error(fmt::format(
      "will not replace '{}': it is {} (name a regular file, or a new one)", path, what));
}

void write_file_atomically(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& f) { f.write(text.data(), static_cast<std::streamsize>(text.size())); });
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  if (!comm::root()) return;   // a distributed run's files are rank 0's to write
  check_replaceable(path);
  const std::string tmp = fmt::format("{}.tmp-{}", path, ::getpid());
  {
    errno = 0;
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) {   // (its folder missing, or not writable: errno says)
      const int err = errno;
      throw std::runtime_error(fmt::format("cannot write '{}': {}", path, err ? std::strerror(err) : "cannot open it"));
    }
    errno = 0;
    try {
      write(f);
    } catch (...) {
      f.close();
      std::remove(tmp.c_str());
      throw;
    }
    f.close();
    if (!f) {
      const int err = errno;
      std::remove(tmp.c_str());
      throw std::runtime_error(fmt::format("cannot write '{}': {}", path, err ? std::strerror(err) : "write failed"));
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    throw std::runtime_error(fmt::format("cannot write '{}': {}", path, std::strerror(err)));
  }
}

}  // namespace trubal

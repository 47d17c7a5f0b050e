#include "io/atomic_file.hpp"
#include "support/comm.hpp"
#include "support/fd_output.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <mutex>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

namespace trubal {

namespace {

// The temporaries that exist now, for the SIGTERM/SIGHUP handler to remove: fixed slots, written
// before they are marked live, so the handler reads only whole names (it may only call unlink).
struct Pending {
  std::atomic<bool> claimed{false}, live{false};
  char name[4096];
};
Pending pending[32];

extern "C" void remove_pending_and_die(int signal) {
  for (auto& p : pending)
    if (p.live.load()) ::unlink(p.name);
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

// Only where the signal would end the program anyway: under mpirun SIGTERM asks the ranks to stop
// (interp/signals.cpp), and they then finish or fail their writes themselves. Looked at for each
// temporary (one system call), as a handler may come or go.
void install_cleanup_handlers() {
  for (int signal : {SIGTERM, SIGHUP}) {
    struct sigaction now {};
    if (sigaction(signal, nullptr, &now) != 0 || (now.sa_flags & SA_SIGINFO) || now.sa_handler != SIG_DFL) continue;
    struct sigaction sa {};
    sa.sa_handler = remove_pending_and_die;
    sigemptyset(&sa.sa_mask);
    sigaction(signal, &sa, nullptr);
  }
}

int remember(const std::string& name) {
  if (name.size() >= sizeof Pending::name) return -1;
  install_cleanup_handlers();
  for (int k = 0; k < static_cast<int>(std::size(pending)); ++k) {
    bool expected = false;
    if (!pending[k].claimed.compare_exchange_strong(expected, true)) continue;
    std::memcpy(pending[k].name, name.c_str(), name.size() + 1);
    pending[k].live.store(true);
    return k;
  }
  return -1;
}

void forget(int slot) {
  if (slot < 0) return;
  pending[slot].live.store(false);
  pending[slot].claimed.store(false);
}

std::string random_suffix() {
  static const char letters[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
  static std::mutex guard;
  static std::mt19937_64 draw{std::random_device{}()};
  std::lock_guard<std::mutex> lock(guard);
  std::string s(6, 'x');
  for (char& c : s) c = letters[draw() % (sizeof letters - 1)];
  return s;
}

bool all_of(const std::string& s, const char* set) { return !s.empty() && s.find_first_not_of(set) == std::string::npos; }

}  // namespace

void check_replaceable(const std::string& path, bool devices) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return;   // absent (or unreadable: the write will say)
  if (S_ISREG(st.st_mode) || (devices && S_ISCHR(st.st_mode))) return;
  const char* what = S_ISLNK(st.st_mode)    ? "a symbolic link"
                     : S_ISDIR(st.st_mode)  ? "a directory"
                     : S_ISFIFO(st.st_mode) ? "a FIFO (a named pipe: writing to it waits for a reader)"
                                            : "not a regular file";
  throw std::runtime_error(fmt::format(
      "will not replace '{}': it is {} (name a regular file, or a new one)", path, what));
}

void remove_stale_temporaries(const std::string& target) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path t(target);
  const fs::path dir = t.has_parent_path() ? t.parent_path() : fs::path(".");
  const std::string prefix = t.filename().string() + ".tmp-";
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string rest = name.substr(prefix.size());   // PID, or PID-XXXXXX
    const std::size_t dash = rest.find('-');
    const std::string pid_text = rest.substr(0, dash);
    if (!all_of(pid_text, "0123456789") || pid_text.size() > 9) continue;
    if (dash != std::string::npos &&
        (rest.size() - dash - 1 != 6 ||
         !all_of(rest.substr(dash + 1), "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789")))
      continue;
    const pid_t pid = static_cast<pid_t>(std::stol(pid_text));
    if (pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH) fs::remove(entry.path(), ec);   // (a link itself)
  }
}

TemporaryFile::TemporaryFile(const std::string& target) : target_(target) {
  remove_stale_temporaries(target);
  for (int attempt = 0; attempt < 100; ++attempt) {
    path_ = fmt::format("{}.tmp-{}-{}", target, ::getpid(), random_suffix());
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd_ >= 0) break;
    if (errno != EEXIST) break;
  }
  if (fd_ < 0) {
    const int err = errno;
    throw std::runtime_error(fmt::format("cannot write '{}': {}", target, std::strerror(err)));
  }
  slot_ = remember(path_);
}

TemporaryFile::~TemporaryFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!path_.empty()) ::unlink(path_.c_str());
  forget(slot_);
}

bool TemporaryFile::close() {
  const int fd = fd_;
  fd_ = -1;
  return fd < 0 || ::close(fd) == 0;
}

void TemporaryFile::rename_over_target(const std::string& note) {
  if (std::rename(path_.c_str(), target_.c_str()) != 0) {
    const int err = errno;
    throw std::runtime_error(fmt::format("cannot write '{}': {}{}", target_, std::strerror(err), note));
  }
  path_.clear();
  forget(slot_);
  slot_ = -1;
}

void write_file_atomically(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& f) { f.write(text.data(), static_cast<std::streamsize>(text.size())); });
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  if (!comm::root()) return;   // a distributed run's files are rank 0's to write
  check_replaceable(path);
  TemporaryFile tmp(path);   // (its folder missing, or not writable: it says)
  FdOutput buffer(tmp.release());
  std::ostream f(&buffer);
  write(f);   // (what it throws removes the temporary)
  f.flush();
  const bool closed = buffer.close();
  if (!closed || !f)
    throw std::runtime_error(fmt::format("cannot write '{}': {}", path,
                                         buffer.error() ? std::strerror(buffer.error()) : "write failed"));
  tmp.rename_over_target();
}

}  // namespace trubal

// The bytes of a save file (io/save.cpp): the format's versions, the checksum, the streams that
// write and read them, and the layouts of older formats' structs. Used by io/save.cpp alone.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <fmt/format.h>

#include "model/model.hpp"

namespace trubal::save_bytes {

constexpr char kMagic[8] = {'T', 'R', 'U', 'B', 'A', 'L', 'S', 'V'};
// 2: the membrane's pressure and area. 3: the periodic cell's tilts (shear); version 2 files are
// read as cells without tilt. 4: the servo's last measured moments (Space::servo_measured), so
// that a restarted servo takes the steps an unbroken run takes; older files start it from the
// contact table; the cycle the contacts' results are of; a following membrane. 5: walls, their
// motion, servo and last loads, and the ball-wall contacts with their history; the periodic
// axes (mixed periodicity; older files are all periodic or all bounded). 6: the cell's volume where
// the accumulated strain was 0 (the volumetric strain's reference), and the histories (HIST):
// each table's items, period, file, platen range and balls, and the rows it holds in memory, so
// that RESTART resumes them; older files restart with none. 7: the energy terms of the last step
// at its force pass (Model::energy_at_step), so that PRINT energy after RESTART is the saved run's;
// older files print the state as it is until the next step. 8: the walls a servo's area comes from
// (Wall::area_walls; older files keep the servo's own area) and the sample (SAMPLE). 9: the
// contacts' history by name (transfer_contacts), so that a contact law part added later reads
// older files. 10: the materials' rolling resistance (Material::rolling_friction) and the work the
// rolling springs dissipated (Energy::rolling_work); older files have none. 11: the materials'
// capillary bridges (Material::bridge_volume, surface_tension, contact_angle) and the work the
// bridges did (Energy::capillary_work, EnergyAtStep::capillary_ahead); older files have none (the
// bridges' state is history, by name). 12: the balls in the model's order in memory, which need
// not be id order, with SET sort's interval and whether balls were added since the last sort
// (Model::order); older files hold them in id order. 13: the parallel bonds (Model::bonds, each
// array whole) and the energy the broken ones held (Energy::bond_break_work); older files restart
// unbonded.
constexpr std::uint32_t kVersion = 13;
constexpr std::uint32_t kOldestVersion = 2;

// FNV-1a, 64 bit: enough to tell a damaged file from a good one. fnv1a_more goes on from `h`
// (the sum of the bytes before) over n more.
constexpr std::uint64_t kFnvStart = 1469598103934665603ull;
inline std::uint64_t fnv1a_more(std::uint64_t h, const char* p, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) h = (h ^ static_cast<unsigned char>(p[k])) * 1099511628211ull;
  return h;
}
inline std::uint64_t fnv1a(const std::string& data) { return fnv1a_more(kFnvStart, data.data(), data.size()); }

static_assert(sizeof(Damping) == sizeof(DampKind) + sizeof(std::uint32_t) + 5 * sizeof(double), "Damping has hidden padding");
static_assert(sizeof(Material) == 12 * sizeof(double) + 8, "Material has hidden padding");

// A material as format 10 wrote it (Material before the capillary bridges).
struct MaterialV10 {
  double kn, ks, friction, cohesion, density, shear_modulus, poisson, restitution, rolling_friction;
  std::uint8_t has_restitution;
  std::uint8_t unused[7];
};
static_assert(sizeof(MaterialV10) == 9 * sizeof(double) + 8, "MaterialV10 has hidden padding");

// A material as formats 2 to 9 wrote it (Material before the rolling resistance).
struct MaterialV9 {
  double kn, ks, friction, cohesion, density, shear_modulus, poisson, restitution;
  std::uint8_t has_restitution;   // (a byte: a damaged file's other values are refused, not read as a bool)
  std::uint8_t unused[7];
};
static_assert(sizeof(MaterialV9) == 8 * sizeof(double) + 8, "MaterialV9 has hidden padding");

// A save whose contents do not add up (a length past its end, a value out of its range).
[[noreturn]] inline void damaged(const std::string& path) {
  throw std::runtime_error(fmt::format("'{}' is damaged: its contents do not add up (not restarted)", path));
}

// Writes a save's body into a file as it goes (a million balls' body is over a GB: never held
// whole), a buffer at a time, keeping its length and checksum for the header (save_model writes
// them last, in place). A failed write is kept (errno) and ends the writing; failed() tells.
class Writer {
 public:
  explicit Writer(int fd) : fd_(fd) { buf_.reserve(kBuffer); }
  // Into memory (light_state): the bytes are appended to *sink.
  explicit Writer(std::string* sink) : fd_(-1), sink_(sink) {}
  // A struct written whole must have no padding (its bytes would be whatever the stack held, and a
  // save's bytes must not depend on the run): Damping and Material name theirs.
  template <class T> void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(reinterpret_cast<const char*>(&v), sizeof v);
  }
  template <class T> void vec(const std::vector<T>& v) {
    pod<std::uint64_t>(v.size());
    if (!v.empty()) bytes(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  void str(const std::string& s) {
    pod<std::uint64_t>(s.size());
    bytes(s.data(), s.size());
  }
  // A piece of a vector's elements: vec's bytes for a vector written its length first (pod), then
  // its elements a piece at a time.
  template <class T> void piece(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (!v.empty()) bytes(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  // Writes what the buffer holds; false (errno kept) where a write failed, now or before.
  bool flush() {
    if (!error_ && !buf_.empty()) put(buf_.data(), buf_.size());
    buf_.clear();
    return !error_;
  }
  std::uint64_t size() const { return size_; }
  std::uint64_t sum() const { return sum_; }   // fnv1a of the body
  int error() const { return error_; }

 private:
  static constexpr std::size_t kBuffer = std::size_t{1} << 20;
  void bytes(const char* p, std::size_t n) {
    sum_ = fnv1a_more(sum_, p, n);
    size_ += n;
    if (buf_.size() + n <= kBuffer) {
      buf_.append(p, n);
      return;
    }
    flush();
    if (n < kBuffer) buf_.append(p, n);
    else if (!error_) put(p, n);   // a large array straight from its memory
  }
  void put(const char* p, std::size_t n) {
    if (sink_) {
      sink_->append(p, n);
      return;
    }
    while (n > 0) {
      const ssize_t w = ::write(fd_, p, n);
      if (w < 0) {
        if (errno == EINTR) continue;
        error_ = errno;
        return;
      }
      p += w;
      n -= static_cast<std::size_t>(w);
    }
  }
  int fd_;
  std::string* sink_ = nullptr;
  std::string buf_;
  std::uint64_t size_ = 0, sum_ = kFnvStart;
  int error_ = 0;
};

// Reads a save's body from memory (light_state's bytes), or from a file a buffer at a time (a
// million balls' body is over a GB: never held whole beside the model made of it).
class Reader {
 public:
  Reader(const std::string& data, const std::string& path) : mem_(data.data()), size_(data.size()), path_(path) {}
  // `size` bytes of body from the file's offset now (which the caller has checked are there).
  Reader(std::FILE* file, std::uint64_t size, const std::string& path) : file_(file), size_(size), path_(path) {}
  template <class T> void pod(T& v) { take(&v, sizeof v); }
  // A bool is one byte, 0 or 1: any other byte would be a bool with no value (undefined behaviour).
  void pod(bool& v) {
    std::uint8_t byte = 0;
    pod(byte);
    if (byte > 1) corrupt();
    v = byte != 0;
  }
  template <std::size_t N> void pod(std::array<bool, N>& v) {
    for (bool& b : v) pod(b);
  }
  template <class T> void vec(std::vector<T>& v) {
    const std::uint64_t n = length_of<T>();
    v.resize(n);
    if (n) take(v.data(), n * sizeof(T));
  }
  void str(std::string& s) {
    std::uint64_t n = 0;
    pod(n);
    need(n);
    s.resize(n);
    take(s.data(), n);
  }
  // A vector's length, then its elements read into v (keep) or passed over, v left empty; either
  // way where its elements lie in the body (at, the count n) is recorded in *spans (a distributed
  // RESTART reads them again, a piece at a time: SavedTables, io/save.hpp).
  struct Span {
    const void* array = nullptr;   // the vector it was read for
    std::uint64_t at = 0, n = 0;
    std::size_t size = 0;          // of an element
  };
  template <class T> void vec_at(std::vector<T>& v, std::vector<Span>& spans, bool keep) {
    const std::uint64_t n = length_of<T>();
    spans.push_back({&v, pos_, n, sizeof(T)});
    if (!keep) {
      skip(n * sizeof(T));
      std::vector<T>().swap(v);
      return;
    }
    v.resize(n);
    if (n) take(v.data(), n * sizeof(T));
  }
  bool at_end() const { return pos_ == size_; }
  const std::string& path() const { return path_; }
  [[noreturn]] void corrupt() const { damaged(path_); }

 private:
  // A vector's length (of elements of T), checked against the bytes left.
  template <class T> std::uint64_t length_of() {
    std::uint64_t n = 0;
    pod(n);
    if (n > (size_ - pos_) / sizeof(T)) corrupt();
    return n;
  }
  void need(std::uint64_t n) const {
    if (n > size_ - pos_) corrupt();
  }
  // Passes over n bytes (checked to be there): those the buffer holds, then the file's beyond it.
  void skip(std::uint64_t n) {
    need(n);
    if (mem_) {
      pos_ += n;
      return;
    }
    const std::uint64_t held = std::min<std::uint64_t>(n, buf_.size() - at_);
    at_ += static_cast<std::size_t>(held);
    pos_ += held;
    const std::uint64_t rest = n - held;
    if (rest == 0) return;
    if (std::fseek(file_, static_cast<long>(rest), SEEK_CUR) != 0)
      throw std::runtime_error(fmt::format("cannot read '{}': {} (not restarted)", path_, std::strerror(errno)));
    read_ += rest;
    pos_ += rest;
  }
  void take(void* to, std::size_t n) {
    need(n);
    char* out = static_cast<char*>(to);
    if (mem_) {
      std::memcpy(out, mem_ + pos_, n);
      pos_ += n;
      return;
    }
    while (n > 0) {
      if (at_ == buf_.size()) refill();
      const std::size_t k = std::min(n, buf_.size() - at_);
      std::memcpy(out, buf_.data() + at_, k);
      at_ += k;
      out += k;
      n -= k;
      pos_ += k;
    }
  }
  void refill() {
    const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(kBuffer, size_ - read_));
    buf_.resize(want);
    const std::size_t got = want > 0 ? std::fread(buf_.data(), 1, want, file_) : 0;
    if (got != want)   // (the file was checked whole: it changed, or the disk failed, since)
      throw std::runtime_error(fmt::format("cannot read '{}': {} (not restarted)", path_,
                                           std::ferror(file_) ? std::strerror(errno) : "it was cut short while read"));
    read_ += got;
    at_ = 0;
  }
  static constexpr std::size_t kBuffer = std::size_t{1} << 20;
  const char* mem_ = nullptr;   // the body in memory, or
  std::FILE* file_ = nullptr;   // the file it is read from
  std::uint64_t size_ = 0;      // the body's length
  std::string path_;
  std::uint64_t pos_ = 0;       // the bytes taken
  std::vector<char> buf_;       // the file's bytes read, at_ of them taken
  std::size_t at_ = 0;
  std::uint64_t read_ = 0;      // the body's bytes read from the file
};

}  // namespace trubal::save_bytes

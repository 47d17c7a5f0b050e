#include "cycle/team.hpp"

#include <algorithm>
#include <stdexcept>
#include <thread>

#include "support/comm.hpp"

namespace trubal {
namespace {

class RankTeam final : public Team {
 public:
  int size() const override { return comm::size(); }
  int rank() const override { return comm::rank(); }
  bool shares_whole() const override { return false; }
  void allgather(const std::vector<double>& mine, std::vector<double>& all) override { comm::allgather(mine, all); }
  void allgather(const std::vector<std::uint8_t>& mine, std::vector<std::uint8_t>& all) override {
    comm::allgather(mine, all);
  }
  void exchange(const std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& recv) override {
    comm::exchange(send, recv);
  }
  void max_all(std::vector<double>& values) override { comm::max_all(values); }
  void barrier() override {
    std::vector<double> none;
    comm::max_all(none);
  }
};

}  // namespace

void SpinBarrier::arrive_and_wait() {
  auto check = [&] {
    if (aborted_.load(std::memory_order_acquire)) throw TeamAborted();
  };
  check();
  const std::uint32_t generation = generation_.load(std::memory_order_acquire);
  if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == members_) {   // the last: release the others
    arrived_.store(0, std::memory_order_relaxed);
    generation_.store(generation + 1, std::memory_order_release);
    generation_.notify_all();   // (no system call unless someone sleeps)
    return;
  }
  // Spin a while (the others are usually a few microseconds behind), then yield a little, then
  // sleep on the word (a futex): where the machine has more runnable threads than cores (another
  // program busy on one), a waiter that kept spinning would take the time the late member needs.
  for (int spins = 0; generation_.load(std::memory_order_acquire) == generation; ++spins) {
#if defined(__x86_64__) || defined(__i386__)
    if (spins < 4096) { __builtin_ia32_pause(); continue; }
#endif
    check();
    if (spins < 4096 + 64) std::this_thread::yield();
    else generation_.wait(generation, std::memory_order_acquire);
  }
  check();   // (an abort also changes the word)
}

Team& rank_team() {
  static RankTeam team;
  return team;
}

// Each operation: publish this member's data, wait for all, read the others', wait again (so no
// member publishes the next operation's data while another still reads this one's).
void ThreadTeam::allgather(const std::vector<double>& mine, std::vector<double>& all) {
  shared_->parts[rank_] = &mine;
  barrier();
  all.clear();
  for (const auto* part : shared_->parts) all.insert(all.end(), part->begin(), part->end());
  barrier();
}

void ThreadTeam::allgather(const std::vector<std::uint8_t>& mine, std::vector<std::uint8_t>& all) {
  shared_->byte_parts[rank_] = &mine;
  barrier();
  all.clear();
  for (const auto* part : shared_->byte_parts) all.insert(all.end(), part->begin(), part->end());
  barrier();
}

void ThreadTeam::exchange(const std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& recv) {
  shared_->sends[rank_] = &send;
  barrier();
  for (int r = 0; r < size(); ++r) {
    const std::vector<double>& from = (*shared_->sends[r])[rank_];
    std::copy(from.begin(), from.end(), recv[r].begin());
  }
  barrier();
}

void ThreadTeam::max_all(std::vector<double>& values) {
  const std::vector<double> mine = values;
  shared_->parts[rank_] = &mine;
  barrier();
  for (const auto* part : shared_->parts)
    for (std::size_t q = 0; q < values.size() && q < part->size(); ++q) values[q] = std::max(values[q], (*part)[q]);
  barrier();
}

}  // namespace trubal

// The members that share a spatially decomposed step (cycle/brick_step.hpp), and the few collective
// operations they use. Two kinds:
// - the ranks of a distributed run (BACKEND mpi): each rank is a process with its own copy of the
//   whole model, and the operations are MPI's (support/comm.hpp);
// - the threads of one process (BACKEND threaded where the balls' numbering is far from their
//   places, cycle/pipeline.cpp): one whole model that every member reads, the operations through
//   shared memory and a barrier (SpinBarrier). Every member must call every collective operation, in the same
//   order, as MPI's ranks do; each member runs on a thread of its own (ThreadPool::run).
#pragma once

#include <atomic>
#include <cstdint>
#include <stdexcept>
#include <cstddef>
#include <vector>

namespace trubal {

class Team {
 public:
  virtual ~Team() = default;
  virtual int size() const = 0;
  virtual int rank() const = 0;
  // The members read and write one whole model (threads), not a copy each (ranks): what a member
  // writes into it is then only its own part, and the model's single values (energies, the walls'
  // loads) only member 0's.
  virtual bool shares_whole() const = 0;
  // Every member's part in member order, concatenated into `all` (part sizes may differ).
  virtual void allgather(const std::vector<double>& mine, std::vector<double>& all) = 0;
  virtual void allgather(const std::vector<std::uint8_t>& mine, std::vector<std::uint8_t>& all) = 0;
  // send[r] goes to member r, and recv[r] (already sized to what member r sends this one) is filled from it.
  virtual void exchange(const std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& recv) = 0;
  // The largest of each member's values, element by element, on every member.
  virtual void max_all(std::vector<double>& values) = 0;
  // Every member has come this far (what was written before is read after by any member).
  virtual void barrier() = 0;
};

// The ranks of this process's MPI run (one member where there is no run).
Team& rank_team();

// A barrier for the threads of one step: a member that arrives early spins (the pause instruction,
// 4096 times, then yielding its core a little), because the members meet four times a step, a few
// hundred microseconds apart, and a futex sleep and wake each time costs more than such a wait;
// past that it sleeps on a futex, so that where the machine has more busy threads than cores a
// waiter does not take the time the late member needs.
// What a member waiting at an aborted barrier throws.
struct TeamAborted : std::runtime_error {
  TeamAborted() : std::runtime_error("another thread of the step failed") {}
};

// A member that fails (an exception) calls abort(): the others, waiting or arriving later, throw
// instead of waiting for it forever; reset() (while no member is inside) makes it whole again.
class SpinBarrier {
 public:
  explicit SpinBarrier(int members) : members_(members) {}
  void arrive_and_wait();
  void abort() {
    aborted_.store(true, std::memory_order_release);
    generation_.fetch_add(1, std::memory_order_acq_rel);   // wakes the sleepers, who then see the abort
    generation_.notify_all();
  }
  void reset() {
    arrived_.store(0, std::memory_order_relaxed);
    aborted_.store(false, std::memory_order_release);
  }

 private:
  const int members_;
  std::atomic<int> arrived_{0};
  std::atomic<std::uint32_t> generation_{0};   // (32 bits: a futex word; it only has to change)
  std::atomic<bool> aborted_{false};
};

// The threads of one process: one ThreadTeam per thread, over one ThreadTeam::Shared.
class ThreadTeam final : public Team {
 public:
  struct Shared {
    explicit Shared(int members)
        : size(members), sync(members), parts(members), byte_parts(members), sends(members) {}
    int size;
    SpinBarrier sync;
    std::vector<const std::vector<double>*> parts;               // per member: its allgather part, max_all values
    std::vector<const std::vector<std::uint8_t>*> byte_parts;    // per member: its allgather part of bytes
    std::vector<const std::vector<std::vector<double>>*> sends;  // per member: its exchange buffers
  };
  ThreadTeam(Shared& shared, int rank) : shared_(&shared), rank_(rank) {}

  int size() const override { return shared_->size; }
  int rank() const override { return rank_; }
  bool shares_whole() const override { return true; }
  void allgather(const std::vector<double>& mine, std::vector<double>& all) override;
  void allgather(const std::vector<std::uint8_t>& mine, std::vector<std::uint8_t>& all) override;
  void exchange(const std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& recv) override;
  void max_all(std::vector<double>& values) override;
  void barrier() override { shared_->sync.arrive_and_wait(); }

 private:
  Shared* shared_;
  int rank_;
};

}  // namespace trubal

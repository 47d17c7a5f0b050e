// The threads' team (cycle/team.hpp): its collective operations give every member what MPI's would,
// and a member that fails releases the others instead of leaving them at the barrier.
#include <catch2/catch.hpp>

#include <chrono>
#include <future>
#include <thread>
#include <vector>

#include "cycle/team.hpp"

using namespace trubal;

namespace {

// f(member) on `members` threads at once; each thread's exception (or none) in member order.
// Catch's assertions are not thread-safe: the threads record, the test's own thread asserts.
template <class F> std::vector<std::exception_ptr> on_threads(int members, F&& f) {
  std::vector<std::exception_ptr> errors(members);
  std::vector<std::thread> threads;
  for (int t = 0; t < members; ++t)
    threads.emplace_back([&, t] {
      try {
        f(t);
      } catch (...) {
        errors[t] = std::current_exception();
      }
    });
  for (auto& thread : threads) thread.join();
  return errors;
}

}  // namespace

TEST_CASE("team: the threads' gather, exchange and max give every member every member's values", "[backends]") {
  constexpr int kMembers = 3;
  ThreadTeam::Shared shared(kMembers);
  std::vector<std::vector<double>> gathered(kMembers), maxima(kMembers);
  std::vector<std::vector<std::vector<double>>> received(kMembers);
  std::vector<int> sizes(kMembers), ranks(kMembers);
  const auto errors = on_threads(kMembers, [&](int me) {
    ThreadTeam team(shared, me);
    sizes[me] = team.size();
    ranks[me] = team.rank();
    for (int round = 0; round < 50; ++round) {   // repeated: no member may overtake a round
      std::vector<double> mine(me + 1, 10.0 * me + round);   // parts of different sizes
      team.allgather(mine, gathered[me]);
      // To member r: r + 1 values saying from whom and to whom.
      std::vector<std::vector<double>> send(kMembers), recv(kMembers);
      for (int r = 0; r < kMembers; ++r) {
        send[r].assign(r + 1, 100.0 * me + r + 1000.0 * round);
        recv[r].resize(me + 1);
      }
      team.exchange(send, recv);
      received[me] = recv;
      std::vector<double> values{static_cast<double>(me), -static_cast<double>(me) + round};
      team.max_all(values);
      maxima[me] = values;
      team.barrier();
    }
  });
  for (const auto& e : errors) CHECK(e == nullptr);
  const int last = 49;
  for (int me = 0; me < kMembers; ++me) {
    INFO("member " << me);
    CHECK(sizes[me] == kMembers);
    CHECK(ranks[me] == me);
    std::vector<double> all;
    for (int r = 0; r < kMembers; ++r) all.insert(all.end(), r + 1, 10.0 * r + last);
    CHECK(gathered[me] == all);
    for (int r = 0; r < kMembers; ++r)
      CHECK(received[me][r] == std::vector<double>(me + 1, 100.0 * r + me + 1000.0 * last));
    CHECK(maxima[me] == std::vector<double>{kMembers - 1.0, 0.0 + last});
  }
}

TEST_CASE("team: a member that fails releases the others from the barrier", "[backends]") {
  // Member 2 fails before the first barrier and aborts; members 0 and 1 must throw TeamAborted
  // instead of waiting for it forever (the test runs under a time limit so that a hang fails).
  constexpr int kMembers = 3;
  ThreadTeam::Shared shared(kMembers);
  auto run = std::async(std::launch::async, [&] {
    return on_threads(kMembers, [&](int me) {
      ThreadTeam team(shared, me);
      if (me == 2) {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));   // the others are waiting by now
        shared.sync.abort();
        throw std::runtime_error("out of memory");
      }
      std::vector<double> mine{1.0}, all;
      team.allgather(mine, all);
    });
  });
  REQUIRE(run.wait_for(std::chrono::seconds(20)) == std::future_status::ready);
  const auto errors = run.get();
  for (int me = 0; me < 2; ++me) {
    INFO("member " << me);
    REQUIRE(errors[me] != nullptr);
    CHECK_THROWS_AS(std::rethrow_exception(errors[me]), TeamAborted);
  }
  REQUIRE(errors[2] != nullptr);
  // Made whole again, the barrier works for the next step.
  shared.sync.reset();
  std::vector<std::size_t> sizes(kMembers);
  const auto again = on_threads(kMembers, [&](int me) {
    ThreadTeam team(shared, me);
    std::vector<double> mine{1.0}, all;
    team.allgather(mine, all);
    sizes[me] = all.size();
  });
  for (int me = 0; me < kMembers; ++me) {
    CHECK(again[me] == nullptr);
    CHECK(sizes[me] == kMembers);
  }
}

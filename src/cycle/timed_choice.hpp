// Whether the threads share a step at all is timed, not predicted: balls numbered so that most
// pairs join distant numbers make a split by numbers slow, small scenes pay more for waking threads
// than any cost model says, and another program busy on one of the cores makes any shared step wait
// for whichever thread the machine has descheduled. A TimedChoice runs a trial of kChunks chunks of
// kChunk steps, shared and on one thread in turn (the first kWarm steps of each chunk not counted:
// data moving between the cores' caches, the parts being made), whenever what it decides for changes
// (the ball count, the threads) and every kRetrial steps; one thread takes over only where its
// median step is kSingleGain times faster than the shared one: a wrong verdict for one thread costs
// up to half the speed, one for sharing a few percent. Every way of taking the step gives the same
// bits, so the verdict only decides the speed.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace trubal {

class TimedChoice {
 public:
  static constexpr int kChunks = 8, kChunk = 16, kWarm = 4;
  static constexpr std::int64_t kRetrial = 20000;
  static constexpr double kSingleGain = 1.05;

  // Whether this step is shared (a trial's chunk, or the last trial's verdict); a trial starts where
  // the ball count or the threads differ from the last trial's or kRetrial steps have passed since it.
  bool shared_now(std::size_t balls, int threads) {
    const std::uint64_t what = static_cast<std::uint64_t>(balls) << 16 ^ static_cast<std::uint64_t>(threads);
    if (step_ == 0 && (what != what_ || ++since_ >= kRetrial)) {
      what_ = what;
      since_ = 0;
      step_ = 1;
      times_[0].clear();
      times_[1].clear();
    }
    if (step_ == 0) return shared_;
    return ((step_ - 1) / kChunk) % 2 == 0;   // chunks shared, single, shared, ...
  }
  bool in_trial() const { return step_ > 0; }
  bool verdict() const { return shared_; }
  // A trial step's time (call only in_trial(), once per step that shared_now() was asked for).
  void record(bool shared, double seconds) {
    if ((step_ - 1) % kChunk >= kWarm) times_[shared ? 1 : 0].push_back(seconds);
    if (++step_ > kChunks * kChunk) {
      step_ = 0;
      shared_ = !(median(times_[0]) * kSingleGain < median(times_[1]));
    }
  }

 private:
  static double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  }
  bool shared_ = true;
  int step_ = 0;                   // 1.. within a trial, 0 outside
  std::vector<double> times_[2];   // step times: [0] one thread, [1] shared
  std::uint64_t what_ = ~std::uint64_t{0};
  std::int64_t since_ = 0;
};

}  // namespace trubal

// The ranks' split (BrickStep::scatter_parts): rank 0 alone reads the whole model. It decomposes
// it, hands every rank the lists every member keeps (the owners, the bisection, each rank's balls,
// pairs, wall contacts and bonds), then cuts each rank's part in turn and sends it, so that it
// holds one part beside the whole model at a time and the others never hold the whole model.
#include "cycle/brick_step_parts.hpp"

#include <cstring>
#include <exception>
#include <new>
#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>

#include "support/comm.hpp"
#include "support/peak_memory.hpp"

namespace trubal {
namespace {

// A part as bytes: each array as its length (8 bytes) and its values, in one fixed order that both
// sides walk (BrickStep::pack_part and unpack_part list it once).
class PartBytes {
 public:
  PartBytes() = default;
  explicit PartBytes(const std::vector<std::uint8_t>& from) : in_(&from) {}
  template <class T> void put(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    word(v.size());
    const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
    out_.insert(out_.end(), p, p + v.size() * sizeof(T));
  }
  template <class T> void take(std::vector<T>& v) {
    const std::uint64_t count = word();
    if (count > (in_->size() - at_) / sizeof(T)) throw std::logic_error("internal error: a part's bytes end early");
    v.resize(count);
    std::memcpy(v.data(), in_->data() + at_, count * sizeof(T));
    at_ += count * sizeof(T);
  }
  void put_word(std::uint64_t w) { word(w); }
  std::uint64_t take_word() { return word(); }
  std::vector<std::uint8_t>& bytes() { return out_; }
  bool at_end() const { return at_ == in_->size(); }

 private:
  void word(std::uint64_t w) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&w);
    out_.insert(out_.end(), p, p + sizeof w);
  }
  std::uint64_t word() {
    std::uint64_t w = 0;
    if (in_->size() - at_ < sizeof w) throw std::logic_error("internal error: a part's bytes end early");
    std::memcpy(&w, in_->data() + at_, sizeof w);
    at_ += sizeof w;
    return w;
  }
  std::vector<std::uint8_t> out_;
  const std::vector<std::uint8_t>* in_ = nullptr;
  std::size_t at_ = 0;
};

// (Each of a list of lists, in order.)
template <class T> void broadcast_lists(std::vector<std::vector<T>>& lists, int count) {
  lists.resize(static_cast<std::size_t>(count));
  for (auto& v : lists) comm::broadcast(v);
}

}  // namespace

void BrickStep::scatter_parts(const Model& full, const VerletReference& ref, const std::function<void()>& fault,
                              const std::string& doing) {
  const int ranks = team_->size();
  const bool root = comm::root();
  together([&] {
    fault();
    if (root) decompose(full);
  }, doing);
  share_decomposition();
  // Each rank's part from rank 0: the length first (-1: rank 0 failed, and the rank goes without),
  // then the rank's word that it could make room (0: it could not), then the bytes.
  std::exception_ptr failure;
  if (root) {
    for (int r = 1; r < ranks; ++r) {
      std::vector<std::uint8_t> bytes;
      if (!failure) {
        try {
          if (r == policy_->fail_cut) {   // (a test's fault)
            policy_->fail_cut = -1;
            throw std::bad_alloc();
          }
          cut_part(full, ref, r);
          bytes = pack_part();
        } catch (...) {
          failure = std::current_exception();
        }
      }
      comm::send_word(r, failure ? -1 : static_cast<std::int64_t>(bytes.size()));
      if (failure) continue;
      if (comm::receive_word(r) != 0) comm::send_bytes(r, bytes);
    }
    if (!failure) {
      try {
        cut_part(full, ref, 0);
      } catch (...) {
        failure = std::current_exception();
      }
    }
  } else {
    const std::int64_t length = comm::receive_word(0);
    if (length < 0) {
      failure = std::make_exception_ptr(std::runtime_error("rank 0 could not make the parts"));
    } else {
      std::vector<std::uint8_t> bytes;
      try {
        bytes.resize(static_cast<std::size_t>(length));
      } catch (...) {
        failure = std::current_exception();
      }
      comm::send_word(0, failure ? 0 : 1);
      if (!failure) {
        comm::receive_bytes(0, bytes);
        try {
          unpack_part(bytes);
        } catch (...) {
          failure = std::current_exception();
        }
      }
    }
  }
  together([&] {
    if (failure) std::rethrow_exception(failure);
  }, fmt::format("making the ranks' parts of the decomposition ({} balls in the whole model)", full.balls.size()));
  return_free_memory();
}

void BrickStep::share_decomposition() {
  // What every member keeps of the split: rank 0's, to the others.
  const int ranks = team_->size();
  comm::broadcast(owner_);
  std::vector<std::uint8_t> cuts(cuts_.size() * sizeof(Cut));
  if (comm::root() && !cuts.empty()) std::memcpy(cuts.data(), cuts_.data(), cuts.size());
  comm::broadcast(cuts);
  cuts_.resize(cuts.size() / sizeof(Cut));
  if (!cuts.empty()) std::memcpy(cuts_.data(), cuts.data(), cuts.size());
  broadcast_lists(rank_balls_, ranks);
  broadcast_lists(rank_pairs_, ranks);
  broadcast_lists(rank_walls_, ranks);
  broadcast_lists(rank_bonds_, ranks);
  comm::broadcast(split_bond_rows_);
  comm::broadcast(split_bond_ball_i_);
  std::vector<double> values{bonded_ ? 1.0 : 0.0, static_cast<double>(bonds_across_), max_radius_,
                             static_cast<double>(full_balls_), walls_any_ ? 1.0 : 0.0};
  comm::broadcast(values);
  bonded_ = values[0] != 0;
  bonds_across_ = static_cast<std::size_t>(values[1]);
  max_radius_ = values[2];
  full_balls_ = static_cast<std::size_t>(values[3]);
  walls_any_ = values[4] != 0;
}

std::vector<std::uint8_t> BrickStep::pack_part() const {
  // What cut_part made of a rank's part, in the order unpack_part reads it.
  PartBytes out;
  Model& part = const_cast<Model&>(part_);
  visit_balls(&part.balls, [&](const auto& v) { out.put(v); });
  out.put_word((part.contacts.history_laws.rolling ? 1 : 0) + (part.contacts.history_laws.bridge ? 2 : 0));
  visit_pairs(&part.contacts, [&](const auto& v) { out.put(v); });
  visit_bonds(&part.bonds, [&](const auto& v) { out.put(v); });
  visit_walls(&part.wall_contacts, [&](const auto& v) { out.put(v); });
  for (const auto* v : {&global_ball_, &owned_, &owned_pairs_, &owned_walls_}) out.put(*v);
  for (const auto& v : send_) out.put(v);
  for (const auto& v : recv_) out.put(v);
  out.put(scratch_.ghost);
  out.put_word(ghosts_);
  for (const auto* v : {&ref_.x, &ref_.y, &ref_.z}) out.put(*v);
  return std::move(out.bytes());
}

void BrickStep::unpack_part(const std::vector<std::uint8_t>& bytes) {
  PartBytes in(bytes);
  const int ranks = team_->size();
  visit_balls(&part_.balls, [&](auto& v) { in.take(v); });
  const std::uint64_t laws = in.take_word();
  part_.contacts.set_history_laws(HistoryLaws{(laws & 1) != 0, (laws & 2) != 0});
  visit_pairs(&part_.contacts, [&](auto& v) { in.take(v); });
  part_.contacts.drop_results();
  visit_bonds(&part_.bonds, [&](auto& v) { in.take(v); });
  visit_walls(&part_.wall_contacts, [&](auto& v) { in.take(v); });
  for (auto* v : {&global_ball_, &owned_, &owned_pairs_, &owned_walls_}) in.take(*v);
  send_.assign(ranks, {});
  recv_.assign(ranks, {});
  for (auto& v : send_) in.take(v);
  for (auto& v : recv_) in.take(v);
  in.take(scratch_.ghost);
  ghosts_ = in.take_word();
  for (auto* v : {&ref_.x, &ref_.y, &ref_.z}) in.take(*v);
  if (!in.at_end()) throw std::logic_error("internal error: a part's bytes go on past its last array");
}

}  // namespace trubal

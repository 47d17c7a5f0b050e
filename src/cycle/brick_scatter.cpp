// The ranks' split (BrickStep::scatter_parts): rank 0 alone reads the whole model. It decomposes
// it, hands every rank the lists every member keeps (the owners, the bisection, each rank's balls,
// pairs, wall contacts and bonds), then cuts each rank's part in turn and sends it, so that it
// holds one part beside the whole model at a time and the others never hold the whole model.
#include "cycle/brick_step_parts.hpp"

#include <algorithm>
#include <cstring>
#include <exception>
#include <new>
#include <numeric>
#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>

#include "physics/scene.hpp"
#include "support/comm.hpp"
#include "support/peak_memory.hpp"

namespace trubal {
namespace {

// (Each of a list of lists, in order.)
template <class T> void broadcast_lists(std::vector<std::vector<T>>& lists, int count) {
  lists.resize(static_cast<std::size_t>(count));
  for (auto& v : lists) comm::broadcast(v);
}

}  // namespace

template <class F> void BrickStep::each_sent_array(F&& f) {
  // What cut_part makes of a rank's part, in one order both sides walk: the balls, the pairs (their
  // history parts those of the whole model's laws, the same on every rank), the bonds, the wall
  // contacts, then the lists of the part and the reference positions.
  send_.resize(static_cast<std::size_t>(team_->size()));
  recv_.resize(static_cast<std::size_t>(team_->size()));
  part_.contacts.set_history_laws(split_laws_);
  visit_balls(&part_.balls, f);
  visit_pairs(&part_.contacts, f);
  visit_bonds(&part_.bonds, f);
  visit_walls(&part_.wall_contacts, f);
  for (auto* v : {&global_ball_, &owned_, &owned_pairs_, &owned_walls_}) f(*v);
  for (auto& v : send_) f(v);
  for (auto& v : recv_) f(v);
  f(scratch_.ghost);
  for (auto* v : {&ref_.x, &ref_.y, &ref_.z}) f(*v);
}

void BrickStep::scatter_parts(const Model& full, const VerletReference& ref, const std::function<void()>& fault,
                              const std::string& doing) {
  const int ranks = team_->size();
  const bool root = comm::root();
  together([&] {
    fault();
    if (root) decompose(full);
  }, doing);
  share_decomposition();
  // Each rank's part from rank 0, straight into its arrays: their lengths first (none: rank 0
  // failed, and the rank goes without), then the rank's word that it could size them (0: it could
  // not), then each array's values.
  std::exception_ptr failure;
  if (root) {
    for (int r = 1; r < ranks; ++r) {
      std::vector<std::uint64_t> lengths;
      if (!failure) {
        try {
          if (r == policy_->fail_cut) {   // (a test's fault)
            policy_->fail_cut = -1;
            throw std::bad_alloc();
          }
          cut_part(full, ref, r);
          each_sent_array([&](auto& v) { lengths.push_back(v.size()); });
        } catch (...) {
          failure = std::current_exception();
        }
      }
      comm::send_word(r, failure ? -1 : static_cast<std::int64_t>(lengths.size()));
      if (failure) continue;
      comm::send_bytes(r, lengths.data(), lengths.size() * sizeof(std::uint64_t));
      if (comm::receive_word(r) == 0) continue;
      each_sent_array([&](auto& v) { comm::send_bytes(r, v.data(), v.size() * sizeof(v[0])); });
    }
    if (!failure) {
      try {
        cut_part(full, ref, 0);
      } catch (...) {
        failure = std::current_exception();
      }
    }
  } else {
    const std::int64_t count = comm::receive_word(0);
    if (count < 0) {
      failure = std::make_exception_ptr(std::runtime_error("rank 0 could not make the parts"));
    } else {
      std::vector<std::uint64_t> lengths(static_cast<std::size_t>(count));
      comm::receive_bytes(0, lengths.data(), lengths.size() * sizeof(std::uint64_t));
      try {
        std::size_t a = 0;
        each_sent_array([&](auto& v) {
          if (a >= lengths.size()) throw std::logic_error("internal error: a part's arrays differ between the ranks");
          v.resize(lengths[a++]);
        });
        if (a != lengths.size()) throw std::logic_error("internal error: a part's arrays differ between the ranks");
      } catch (...) {
        failure = std::current_exception();
      }
      comm::send_word(0, failure ? 0 : 1);
      if (!failure) {
        each_sent_array([&](auto& v) { comm::receive_bytes(0, v.data(), v.size() * sizeof(v[0])); });
        ghosts_ = static_cast<std::size_t>(std::count(scratch_.ghost.begin(), scratch_.ghost.end(), 1));
      }
    }
  }
  together([&] {
    if (failure) std::rethrow_exception(failure);
  }, fmt::format("making the ranks' parts of the decomposition ({} balls in the whole model)", full.balls.size()));
  return_free_memory();
}

void BrickStep::split_from_records(const Model& full, std::vector<double>& records) {
  ++edition_;
  update_shares();   // (a collective call)
  const int ranks = team_->size(), me = team_->rank();
  const std::string doing = fmt::format("making its part of the decomposition ({} balls in the whole model)", full.balls.size());
  together([&] {
    if (comm::root()) decompose(full);
  }, doing);
  share_decomposition();
  // Each ball to its owner: the counts first (each rank's to each, gathered), then the records.
  std::vector<std::vector<double>> send(static_cast<std::size_t>(ranks)), recv(static_cast<std::size_t>(ranks));
  together([&] {
    for (std::size_t r = 0; r + kRecord <= records.size(); r += kRecord) {
      auto& to = send[owner_[static_cast<std::size_t>(records[r])]];
      to.insert(to.end(), records.begin() + static_cast<std::ptrdiff_t>(r),
                records.begin() + static_cast<std::ptrdiff_t>(r + kRecord));
    }
    std::vector<double>().swap(records);
  }, doing);
  std::vector<double> counts, all;
  for (const auto& v : send) counts.push_back(static_cast<double>(v.size()));
  comm::allgather(counts, all);
  for (int r = 0; r < ranks; ++r) recv[r].resize(static_cast<std::size_t>(all[static_cast<std::size_t>(r * ranks + me)]));
  comm::exchange(send, recv);
  std::vector<std::vector<double>>().swap(send);
  together([&] {
    split_fault();   // (a rank's test fault, as split's)
    // The part: this rank's balls in the whole model's order (rank_balls_ ascends), at rest, their
    // masses from their types' densities as a CYCLE sets the whole model's.
    const std::vector<std::uint32_t>& mine = rank_balls_[me];
    const std::size_t m = mine.size();
    Balls& b = part_.balls;
    b.for_each_array([&](auto& v) {
      std::decay_t<decltype(v)>().swap(v);
      v.resize(m);
    });
    std::size_t placed = 0;
    for (const auto& from : recv)
      for (std::size_t r = 0; r + kRecord <= from.size(); r += kRecord) {
        const auto k = static_cast<std::uint32_t>(from[r]);
        const auto at = std::lower_bound(mine.begin(), mine.end(), k);
        if (at == mine.end() || *at != k) throw std::logic_error("internal error: a ball came to a rank that does not own it");
        const auto q = static_cast<std::size_t>(at - mine.begin());
        b.id[q] = row_id(from[r + 1]);
        b.type[q] = static_cast<int>(from[r + 2]);
        b.x[q] = from[r + 3];
        b.y[q] = from[r + 4];
        b.z[q] = from[r + 5];
        b.rad[q] = from[r + 6];
        ++placed;
      }
    if (placed != m) throw std::logic_error("internal error: a rank's balls did not all come");
    std::vector<std::vector<double>>().swap(recv);
    part_.materials = full.materials;
    update_mass(part_);
    own_balls_alone(mine);
  }, doing);
  finish_part(full);
  return_free_memory();
}

void BrickStep::own_balls_alone(const std::vector<std::uint32_t>& mine) {
  const std::size_t m = mine.size();
  const int ranks = team_->size();
    part_.contacts.for_each_pair_array([](auto& v) { std::decay_t<decltype(v)>().swap(v); });
    part_.contacts.set_history_laws(split_laws_);
    part_.bonds.for_each_array([](auto& v) { std::decay_t<decltype(v)>().swap(v); });
    part_.wall_contacts.for_each_array([](auto& v) { std::decay_t<decltype(v)>().swap(v); });
    global_ball_ = mine;
    owned_.resize(m);
    std::iota(owned_.begin(), owned_.end(), 0u);
    owned_pairs_.clear();
    owned_walls_.clear();
    send_.assign(static_cast<std::size_t>(ranks), {});
    recv_.assign(static_cast<std::size_t>(ranks), {});
    scratch_.ghost.assign(m, 0);
    ghosts_ = 0;
  // (No reference positions: the search about to be made sets them, or where it goes through
  // the whole model, reference_at_balls.)
  ref_.x.clear();
  ref_.y.clear();
  ref_.z.clear();
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
  // (Each rank's pairs' and wall contacts' places in the whole model's tables are rank 0's alone to
  // read: it places the values the others send, sync. A whole model's list is 4 bytes a pair.)
  if (!comm::root()) {
    rank_pairs_.assign(static_cast<std::size_t>(ranks), {});
    rank_walls_.assign(static_cast<std::size_t>(ranks), {});
  }
  broadcast_lists(rank_bonds_, ranks);
  comm::broadcast(split_bond_rows_);
  comm::broadcast(split_bond_ball_i_);
  std::vector<double> values{bonded_ ? 1.0 : 0.0, static_cast<double>(bonds_across_), max_radius_,
                             static_cast<double>(full_balls_), walls_any_ ? 1.0 : 0.0,
                             split_laws_.rolling ? 1.0 : 0.0, split_laws_.bridge ? 1.0 : 0.0,
                             static_cast<double>(split_off_.intact), static_cast<double>(split_off_.tension),
                             static_cast<double>(split_off_.shear)};
  comm::broadcast(values);
  bonded_ = values[0] != 0;
  bonds_across_ = static_cast<std::size_t>(values[1]);
  max_radius_ = values[2];
  full_balls_ = static_cast<std::size_t>(values[3]);
  walls_any_ = values[4] != 0;
  split_laws_ = HistoryLaws{values[5] != 0, values[6] != 0};
  split_off_ = BondCounts{static_cast<std::size_t>(values[7]), static_cast<std::size_t>(values[8]),
                          static_cast<std::size_t>(values[9])};
}

}  // namespace trubal

// SAVE/RESTART: the whole model (balls, materials, contacts with their shear history, space,
// settings, energy, groups, histories) in a versioned binary file with a checksum, written atomically.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <cstdio>

#include "io/history.hpp"
#include "model/model.hpp"
#include "model/table_pieces.hpp"

namespace trubal {

// The contact results of a model whose table does not hold them: a distributed run's, which a
// CYCLE deferred, made on the ranks' parts (Pipeline::results_on_parts), fetched one array at a
// time as SAVE writes it, so that rank 0 holds one of them at a time, not all. fetch: array k of
// ContactTable::for_each_result_array's order (the first, `state`, bytes; the others reals), of
// the table's length.
class ResultSource {
 public:
  virtual ~ResultSource() = default;
  virtual void fetch(std::size_t k, std::vector<std::uint8_t>& into) = 0;
  virtual void fetch(std::size_t k, std::vector<double>& into) = 0;
  // The cycle whose step's force pass they are of (ContactTable::results_cycle).
  virtual std::int64_t cycle() const = 0;
};

// Where the model's arrays do not hold its state (a distributed run's rank 0 whose whole model is
// hollow: the ranks' kept parts alone hold it), the state SAVE writes from them, each array streamed
// in the whole model's order a chunk at a time, so that rank 0 holds a chunk, not the model. The
// tables: the balls (array k of Balls::for_each_array, where the model's is empty), the pairs SAVE
// keeps and the wall contacts, each table's arrays in SAVE's order (the list's, every declared
// history part's, the results'). Values travel as doubles: integers of 32 bits and fewer by value,
// 64-bit ones by their bits.
class StateSource {
 public:
  enum class Table { Balls, Pairs, Walls };
  virtual ~StateSource() = default;
  // The pairs SAVE keeps (touching in the results, or with history) and the wall contacts, placed
  // in the whole model's order: their counts.
  virtual std::uint64_t place_pairs() = 0;
  virtual std::uint64_t place_walls() = 0;
  // Array k of the table, `write(chunk)` for each chunk in order.
  virtual void stream(Table table, std::size_t k, const std::function<void(const std::vector<double>&)>& write) = 0;
  // The cycle of the results the source holds; -1 where it holds none (written as zero).
  virtual std::int64_t results_cycle() const = 0;
};

// Writes to a temporary beside PATH (TemporaryFile, io/atomic_file.hpp), syncs, renames over PATH.
// Throws std::runtime_error on failure (the old file, if any, is untouched).
// With `history`, its tables (settings and the rows in memory) are saved too. `version` 0 writes
// the current format; an older one writes what that format held (for the tests that check that
// older files still read). `results`: where the table's results are, where it does not hold them
// (the same bytes as from a table that does).
// `state`: where the model's state is (the current format only).
void save_model(const Model& model, const std::string& path, const History* history = nullptr,
                std::uint32_t version = 0, ResultSource* results = nullptr, StateSource* state = nullptr);
// Reads a file written by save_model. Throws std::runtime_error for a missing, truncated,
// corrupted or foreign file, or one of another version; the model is not touched then. With
// `history`, it receives the saved tables (none from a file older than version 6), their files not
// yet opened (History::resume_files).
Model load_model(const std::string& path, History* history = nullptr);

// A save read for a distributed RESTART (Session::restart), whose ranks take their parts of its
// bulk from rank 0 a piece at a time (BrickStep::split_from_file), so that no rank holds the whole
// model. Made, it has checked the file whole (its checksum) and read all of it but the bulk: its
// model (take_model) holds the balls' ids, types, fixities, radii and centres alone, no pair and
// no wall contact; where the rest lies in the file is kept, and read() reads any piece of it again
// (TablePieces). Throws as load_model.
class SavedTables final : public TablePieces {
 public:
  SavedTables(const std::string& path, History* history);
  ~SavedTables() override;
  SavedTables(const SavedTables&) = delete;
  SavedTables& operator=(const SavedTables&) = delete;
  // "" where the ranks' parts can be made from the file; else why not (then load_model reads it):
  // a format before 12 (the balls in id order), bonds, a membrane, no ball, or pairs whose
  // contact results are not of the model's cycle (the parts hold results of the model's state).
  const std::string& why_whole() const { return why_whole_; }
  // Checks every value load_model checks, the bulk read a piece at a time, and takes the contact
  // history parts into use as load_model does, `piece` rows of a table at a time. Throws as
  // load_model, the same message.
  void check(std::uint64_t piece = std::uint64_t{1} << 16);
  // The model (once): the balls' ids, types, fixities, radii and centres, no pair, no wall contact.
  Model take_model();
  std::uint64_t rows(PieceTable table) const override;
  void read(PieceTable table, std::size_t k, std::uint64_t from, std::uint64_t n, void* out, std::size_t size) override;

 private:
  struct Span {
    std::uint64_t at = 0, n = 0;   // the elements' place in the body, their count
    std::size_t size = 0;          // of an element; 0: no such array in the file
  };
  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t body_at_ = 0;   // the header's length
  Model model_;
  std::vector<Span> spans_[3];   // by PieceTable, array k
  std::string why_whole_;
};

// The model but its bulk (the balls, the pairs, the walls' contacts, the bonds), as bytes in SAVE's
// layout, and a model made of them (without balls): what the ranks other than 0 of a distributed
// run hold of rank 0's model after a command that rank 0 alone ran, with the balls' ids, types and
// radii (Session::light_everywhere). It goes through SAVE's list of what a model holds, so nothing
// SAVE keeps is left behind. light_state changes nothing (the bulk is set aside while it writes).
std::string light_state(const Model& model);
void take_light_state(Model& model, const std::string& bytes);
// The histories' tables (settings and rows) as bytes in SAVE's layout, and the tables made of them:
// what the ranks other than 0 take of the histories rank 0 alone read (Session::restart).
std::string history_bytes(const History& history);
void take_history_bytes(History& history, const std::string& bytes);

}  // namespace trubal

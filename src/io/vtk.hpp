// DUMP vtk: ParaView files. Each dump writes two VTK XML PolyData files, named by the cycle,
//   BASE_000123.vtp           balls: points at the centres, one vertex cell each; point data id,
//                             type, radius, velocity, spin, force
//   BASE_contacts_000123.vtp  force chains: one line cell per touching pair, from centre to centre;
//                             cell data normal_force (magnitude), force (vector on j), id_i, id_j
// and, when the model has walls, a third,
//   BASE_walls_000123.vtp     walls: polygon cells; a plane as a square centred on its point, side
//                             the START box's diagonal; a polygon as one cell of its vertices; a
//                             cylinder as kCylinderSegments quads around, one band along its length,
//                             facing out; cell data id (the wall's), force (on the wall)
// and, in every dump,
//   BASE_domain_000123.vtp    the START box or periodic cell (a parallelepiped once sheared): its 8
//                             corners and 12 edges as line cells; cell data axis (0 1 2, the edge's
//                             direction) and periodic (1 where that axis is periodic)
// and, when the model has bonds (BOND),
//   BASE_bonds_000123.vtp     the parallel bonds: each broken bond a vertex cell (a crack) at the
//                             middle of the gap between its balls' surfaces, then each intact bond a
//                             line cell from centre to centre; cell data state (0 intact, 1 broken
//                             in tension, 2 in shear), normal_force (compression positive; a
//                             crack's, what broke it), id_i, id_j
// and rewrites BASE.pvd, the collection (part 0 balls, part 1 contacts, part 2 walls where a dump
// has them, part 3 the domain, part 4 the bonds where a dump has them) with each dump's time, so ParaView opens the whole series at once. Arrays are binary, appended raw (little-endian, UInt64
// byte counts). Every file is written to a temporary name and renamed, so a reader never sees
// half a file.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "model/model.hpp"
#include "model/dump_rows.hpp"

namespace trubal {

// The quads around a cylinder wall in the walls file.
inline constexpr int kCylinderSegments = 48;

// Writes the wall, domain and bond files of one dump. Throws std::runtime_error if a file cannot
// be written.
void write_walls_vtp(const Model& model, const std::string& path);
void write_domain_vtp(const Model& model, const std::string& path);
void write_bonds_vtp(const Model& model, const std::string& path);

// Where a dump's balls and lines come from: the model's arrays (ModelRows), or a distributed run's
// kept parts, every rank calling VtkSeries::write alike (each pass a collective call: the rows
// merged to rank 0 in order), rank 0 alone writing the files (writes()).
class VtkRows {
 public:
  using Take = std::function<void(const double*)>;
  virtual ~VtkRows() = default;
  virtual bool writes() const { return true; }
  virtual std::uint64_t lines() = 0;   // the touching pairs, over the whole model
  // take(row) for each row in order, where writes() (else nullptr).
  virtual void ball_rows(const Take& take) = 0;
  virtual void line_rows(const Take& take) = 0;
};

// The rows of a model that holds its balls and contacts.
class ModelRows final : public VtkRows {
 public:
  explicit ModelRows(const Model& model) : model_(model) {}
  std::uint64_t lines() override;
  void ball_rows(const Take& take) override;
  void line_rows(const Take& take) override;

 private:
  const Model& model_;
};

class VtkSeries {
 public:
  // BASE is the file name without extension (a .vtp or .pvd given is dropped).
  explicit VtkSeries(std::string base, std::int64_t every = 0);
  // Writes one dump of the model now and adds it to the collection; the balls and lines from
  // `rows` where given (the model's light state the rest), every pass of it run however a file
  // fails (the first failure thrown after). Without writes(), the passes alone and the entry.
  void write(const Model& model, VtkRows* rows = nullptr);
  // True when periodic dumps are on and this cycle is due.
  bool due(std::int64_t cycle) const { return every_ > 0 && cycle % every_ == 0; }
  const std::string& base() const { return base_; }
  std::int64_t every() const { return every_; }
  void set_every(std::int64_t every) { every_ = every; }
  std::string pvd_path() const { return base_ + ".pvd"; }
  // The file names of the dump at a cycle.
  std::string balls_path(std::int64_t cycle) const;
  std::string contacts_path(std::int64_t cycle) const;
  std::string walls_path(std::int64_t cycle) const;   // written only when the model has walls
  std::string domain_path(std::int64_t cycle) const;
  std::string bonds_path(std::int64_t cycle) const;   // written only when the model has bonds
  std::size_t dumps() const { return entries_.size(); }

 private:
  struct Entry {
    std::int64_t cycle;
    double time;
    bool walls;   // a walls file was written
    bool bonds;   // a bonds file was written
  };
  void write_pvd() const;
  std::string base_;
  std::int64_t every_;
  std::vector<Entry> entries_;
};

}  // namespace trubal

#include "backends/serial/serial_backend.hpp"

#include "backends/periodic_pairs.hpp"
#include "backends/serial/box_grid.hpp"
#include "support/format_number.hpp"

namespace trubal {
namespace {

class SerialBackend final : public Backend {
 public:
  std::string name() const override { return "serial"; }

  void find_pairs(const Model& model, double skin, ThreadPool&, PairCandidates& out) override {
    out.periodic_bins = {};
    find_serial_pairs(model, skin, grid_, out);
    periodic_bins_ = out.periodic_bins;
  }

  std::vector<std::pair<std::string, std::string>> info() const override { return box_info(grid_.dims(), grid_.cell_size(), periodic_bins_); }

 private:
  BoxGrid grid_;
  std::array<int, 3> periodic_bins_{};   // of the last search, where it was the periodic one
};

}  // namespace

std::unique_ptr<Backend> make_serial_backend() { return std::make_unique<SerialBackend>(); }

void find_serial_pairs(const Model& model, double skin, BoxGrid& grid, PairCandidates& out, std::size_t i_begin,
                       std::size_t i_end) {
  const Balls& b = model.balls;
  if (model.space.periodic) {
    find_periodic_pairs(model, skin, out, nullptr, i_begin, i_end);
    return;
  }
  grid.fill(b, 2 * b.max_radius() + skin, model.space.boxes);
  grid.find_pairs(b, skin, out, i_begin, i_end);
}

}  // namespace trubal

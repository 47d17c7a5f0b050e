#include "model/dump_rows.hpp"

#include <bit>
#include <cmath>
#include <cstdint>

namespace trubal {

void vtk_ball_row(const Balls& b, std::size_t k, double* row) {
  row[0] = 0;
  row[1] = b.x[k], row[2] = b.y[k], row[3] = b.z[k];
  row[4] = std::bit_cast<double>(static_cast<std::int64_t>(b.id[k]));
  row[5] = static_cast<double>(b.type[k]);
  row[6] = b.rad[k];
  row[7] = b.vx[k], row[8] = b.vy[k], row[9] = b.vz[k];
  row[10] = b.wx[k], row[11] = b.wy[k], row[12] = b.wz[k];
  row[13] = b.fx[k], row[14] = b.fy[k], row[15] = b.fz[k];
}

bool vtk_line(const Model& model, std::size_t p) {
  const ContactTable& c = model.contacts;
  return c.touching(p) && c.i[p] < model.balls.x.size() && c.j[p] < model.balls.x.size();
}

bool vtk_line_row(const Model& model, const CellFrame& frame, std::size_t p, double* row) {
  if (!vtk_line(model, p)) return false;
  const Balls& b = model.balls;
  const ContactTable& c = model.contacts;
  const std::size_t i = c.i[p], j = c.j[p];
  // j as seen from i: across the periodic cell when the contact is with an image.
  double shift[3] = {0.0, 0.0, 0.0};
  if (model.space.periodic) image_offset(frame, c.image_x[p], c.image_y[p], c.image_z[p], shift[0], shift[1], shift[2]);
  row[0] = 0;
  row[1] = b.x[i], row[2] = b.y[i], row[3] = b.z[i];
  row[4] = b.x[j] + shift[0], row[5] = b.y[j] + shift[1], row[6] = b.z[j] + shift[2];
  row[7] = std::abs(c.fn[p]);
  row[8] = c.fx[p], row[9] = c.fy[p], row[10] = c.fz[p];
  row[11] = std::bit_cast<double>(static_cast<std::int64_t>(b.id[i]));
  row[12] = std::bit_cast<double>(static_cast<std::int64_t>(b.id[j]));
  return true;
}

}  // namespace trubal

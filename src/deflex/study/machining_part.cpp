// The machining study's part, tool, slot cuts and probing plan (see detail/machining_part.hpp).
#include "deflex/study/detail/machining_part.hpp"

#include <cmath>

#include "deflex/model/types.hpp"

namespace deflex::study {
namespace {

constexpr double kMillMm = 1e-3;
// The tool's tip starts and ends this far beyond the stock's ends (its radius and a millimetre):
// every pass enters the material from the air.
constexpr double kRunIn = 6.0 * kMillMm;
// The dexel stock's line spacing: 0.05 and 0.2 mm move the walls by under 3 um and take longer
// (the force's ripple at 0.2 mm takes the coupled solve more trials).
constexpr double kStockCellM = 0.1e-3;
// The engagement query's sampling: 33 angles on the front half (5.6 deg apart, 9 in a 2 mm side cut's
// arc on the 10 mm tool), the arcs' ends to pi / 32 / 2^12 = 2.4e-5 rad (0.12 um along the edge).
// Against the stock's own 65 angles and 4.7e-8 rad the walls move by under 1.5 um and a study takes a
// third less; 25 angles and 1.3e-4 rad move a finished wall's P-V by 10 um.
constexpr EngagementSampling kStudySampling{32, 12, 10e-6, 1e-6};

cell::WallSpec part_wall(cell::WallSpec::Normal normal, double nominal, bool material_below, double lo, double hi,
                         double depth, int points) {
  cell::WallSpec s;
  s.normal = normal;
  s.nominal_m = nominal;
  s.material_below = material_below;
  s.along_lo_m = lo;
  s.along_hi_m = hi;
  // Half a millimetre clear of the floor's corner and of the top edge's burr.
  s.z_lo_m = -depth + 0.5 * kMillMm;
  s.z_hi_m = -0.5 * kMillMm;
  s.points_along = points;
  s.points_up = 3;
  return s;
}

cell::FloorSpec part_floor(double z, double x_lo, double x_hi, double y_lo, double y_hi) {
  cell::FloorSpec f;
  f.nominal_m = z;
  f.x_lo_m = x_lo;
  f.x_hi_m = x_hi;
  f.y_lo_m = y_lo;
  f.y_hi_m = y_hi;
  f.nx = 10;
  f.ny = 3;
  return f;
}

MillPass straight(const char* name, double y, double z, double length) {
  return MillPass{name, {Vector3(-kRunIn, y, z), Vector3(length + kRunIn, y, z)}};
}

}  // namespace

DexelStock make_stock(const StockBox& box) {
  DexelStock stock = DexelStock::box(box.min_m, box.max_m, box.cell_m, box.layer_m);
  stock.set_sampling(box.sampling);
  return stock;
}

Cutter study_cutter() {
  Cutter c;
  c.diameter_m = 10.0 * kMillMm;
  c.flutes = 3;
  c.helix_rad = deg_to_rad(30.0);
  return c;
}

CuttingCoefficients al7075_published() {
  CuttingCoefficients k;
  k.ktc_n_m2 = 767e6;
  k.krc_n_m2 = 168.8e6;
  k.kac_n_m2 = 222e6;
  k.kte_n_m = 27.7e3;
  k.kre_n_m = 26.6e3;
  k.kae_n_m = 0.7e3;
  return k;
}

// Across y (mm): a 10 mm slot 3 mm deep at y = -13 (walls -18, -8); an open pocket 4 mm deep,
// roughed by a slot at y = 5 and finished 2 mm a side: its wall y = -2 in climb (the material on the
// tool's right, M3), its wall y = 12 in conventional milling; the outside contour 2 mm into the
// block's face y = 20, round the corner at x = L - 2 and down that face in climb.
MillPart make_mill_part(bool quick) {
  const double length = (quick ? 12.0 : 20.0) * kMillMm;
  const int points = quick ? 10 : 20;
  MillPart p;
  p.stock.min_m = Vector3(0.0, -20.0 * kMillMm, -8.0 * kMillMm);
  p.stock.max_m = Vector3(length, 20.0 * kMillMm, 0.0);
  p.stock.cell_m = kStockCellM;
  p.stock.sampling = kStudySampling;
  p.passes.push_back(straight("slot", -13.0 * kMillMm, -3.0 * kMillMm, length));
  p.passes.push_back(straight("pocket rough", 5.0 * kMillMm, -4.0 * kMillMm, length));
  p.passes.push_back(straight("pocket climb finish", 3.0 * kMillMm, -4.0 * kMillMm, length));
  p.passes.push_back(straight("pocket conventional finish", 7.0 * kMillMm, -4.0 * kMillMm, length));
  const double corner_x = length - 2.0 * kMillMm + 5.0 * kMillMm;
  p.passes.push_back(
      MillPass{"contour",
               {Vector3(-kRunIn, 23.0 * kMillMm, -4.0 * kMillMm), Vector3(corner_x, 23.0 * kMillMm, -4.0 * kMillMm),
                Vector3(corner_x, 14.0 * kMillMm, -4.0 * kMillMm)}});
  const double lo = 1.0 * kMillMm, hi = length - 1.0 * kMillMm;
  using N = cell::WallSpec::Normal;
  // The contour's second leg takes the end of the rib between the pocket and the contour: the walls
  // there are probed to 3 mm short of the block's end, all three alike.
  const double rib_hi = length - 3.0 * kMillMm;
  p.climb_wall = part_wall(N::kY, -2.0 * kMillMm, true, lo, rib_hi, 4.0 * kMillMm, points);
  p.conventional_wall = part_wall(N::kY, 12.0 * kMillMm, false, lo, rib_hi, 4.0 * kMillMm, points);
  p.contour_wall = part_wall(N::kY, 18.0 * kMillMm, true, lo, rib_hi, 4.0 * kMillMm, points);
  p.slot_wall_a = part_wall(N::kY, -18.0 * kMillMm, true, lo, hi, 3.0 * kMillMm, points);
  p.slot_wall_b = part_wall(N::kY, -8.0 * kMillMm, false, lo, hi, 3.0 * kMillMm, points);
  p.pocket_floor = part_floor(-4.0 * kMillMm, lo, hi, -1.0 * kMillMm, 11.0 * kMillMm);
  p.slot_floor = part_floor(-3.0 * kMillMm, lo, hi, -17.0 * kMillMm, -9.0 * kMillMm);
  return p;
}

// Slots 10 mm wide and 3 mm deep, 12 mm apart, each from the air into the block and stopped 4 mm
// short of its far end; the force is averaged where the whole front half of the tool is in the cut.
SlotCutPlan make_slot_cut_plan(bool quick) {
  SlotCutPlan s;
  s.fz_m = quick ? std::vector<double>{0.02 * kMillMm, 0.04 * kMillMm, 0.06 * kMillMm}
                 : std::vector<double>{0.02 * kMillMm, 0.035 * kMillMm, 0.05 * kMillMm, 0.065 * kMillMm};
  s.ap_m = 3.0 * kMillMm;
  const double length = 14.0 * kMillMm;
  s.stock.min_m = Vector3(0.0, -6.0 * kMillMm, -6.0 * kMillMm);
  s.stock.cell_m = kStockCellM;
  s.stock.sampling = kStudySampling;
  s.stock.max_m = Vector3(length, (12.0 * static_cast<double>(s.fz_m.size()) - 6.0) * kMillMm, 0.0);
  for (std::size_t i = 0; i < s.fz_m.size(); ++i) {
    const double y = 12.0 * kMillMm * static_cast<double>(i);
    s.passes.push_back(MillPass{"slot cut", {Vector3(-kRunIn, y, -s.ap_m), Vector3(10.0 * kMillMm, y, -s.ap_m)}});
  }
  s.window_from_x_m = 0.5 * kMillMm;
  s.window_to_x_m = 9.0 * kMillMm;
  return s;
}

std::vector<Vector3> sample_pass(const MillPass& pass, double step_m) {
  std::vector<Vector3> out;
  out.push_back(pass.corners.front());
  for (std::size_t i = 1; i < pass.corners.size(); ++i) {
    const Vector3 a = pass.corners[i - 1], b = pass.corners[i];
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step_m)));
    for (int k = 1; k <= n; ++k) {
      out.push_back(a + (b - a) * (static_cast<double>(k) / n));
    }
  }
  return out;
}

}  // namespace deflex::study

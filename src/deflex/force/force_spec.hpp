// Force models from a one-line text specification (command-line option, case file):
//
//   ldbb:pivot_mm=X;Y;Z,force_N=F[;F2;...],mode=push|pull
//   ldbb:phi_deg=A,force_N=F[;F2;...],mode=push|pull        (needs a circle path, see below)
//   constant:fx_N=..,fy_N=..,fz_N=..,mx_Nm=..,my_Nm=..,mz_Nm=..   (absent components are 0)
//   tool:fx_N=..,fy_N=..,fz_N=..,mx_Nm=..,my_Nm=..,mz_Nm=..       (the same, in the TCP frame)
//   table:FILE.csv                                          (see wrench_table_model.hpp)
//   milling:Ktc_N_mm2=..,...[,ae_mm=..,ap_mm=..]           (a toolpath's cutting force, with a cutter:
//   milling:file=COEFFS.yaml[,...]                           machining/milling_force_model.hpp)
//
// Keys are separated by ',' and the components of one value by ';'. Every unit is in the key's
// name; positions in mm, forces in N, moments in Nm (moment about the TCP), base frame (tool: the
// TCP frame, so the wrench turns with the tool, as a drill's thrust does). mode
// defaults to push. Several force_N values give one model per load (the paper's 125;375;625).
//
// phi_deg places the LDBB pivot on the circle's axis so the bar is inclined by phi to the circle's
// plane: pivot = centre - normal * radius * tan(phi), i.e. below the circle for phi > 0 and a normal
// of +z (paper, Figure 4). The bar length is then radius / cos(phi) at every point, as a real DBB
// demands (the ball runs on a sphere round the pivot).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "deflex/force/force_model.hpp"
#include "deflex/model/types.hpp"

namespace deflex {

/// The models of a spec of a process force the force module does not build itself (milling:, the
/// machining module's milling_force_specs(cutter), which knows the cutter and the coefficients).
using ProcessForceSpecs = std::function<std::vector<std::unique_ptr<ForceModel>>(const std::string& spec)>;

/// What the path knows that a spec may refer to.
struct ForceSpecContext {
  std::optional<CircleGeometry> circle;  ///< enables ldbb:phi_deg=... (a CirclePath converts to it)
  ProcessForceSpecs milling;             ///< builds milling: specs with the cutter (--cutter); empty: refused
};

/// Every model the spec describes (more than one only for several force_N values). Throws
/// InputError quoting the spec and the key at fault (unknown or repeated key, bad number, missing
/// key, phi_deg without a circle, milling without a cutter); a table spec throws DataError from the CSV
/// reader, a milling spec's coefficient file ModelError.
[[nodiscard]] std::vector<std::unique_ptr<ForceModel>> parse_force_specs(const std::string& spec,
                                                                         const ForceSpecContext& context = {});

/// Exactly one model; InputError when the spec gives several loads.
[[nodiscard]] std::unique_ptr<ForceModel> parse_force_spec(const std::string& spec,
                                                           const ForceSpecContext& context = {});

/// The LDBB pivot for a bar inclined by phi (rad) to the circle's plane (see the file comment), m.
/// Throws InputError unless |phi| < 89 deg and the circle's normal, centre and radius (> 0) are finite.
[[nodiscard]] Vector3 ldbb_pivot_for_circle(const CircleGeometry& circle, double phi_rad);

}  // namespace deflex

// Parser of force-model specifications.
#include "deflex/force/force_spec.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/force/tool_wrench_model.hpp"
#include "deflex/force/wrench_table_model.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/key_value_spec.hpp"

namespace deflex {
namespace {

std::vector<std::unique_ptr<ForceModel>> parse_ldbb(const std::string& spec, const std::string& body,
                                                    const ForceSpecContext& context) {
  const KeyValueSpec keys(spec, body, {"pivot_mm", "phi_deg", "force_N", "mode"});
  if (!keys.has("force_N")) {
    keys.fail("key 'force_N' (bar force magnitude, N) is required");
  }
  bool push = true;
  if (keys.has("mode")) {
    const std::string& m = keys.text("mode");
    if (m != "push" && m != "pull") {
      keys.fail(fmt::format("key 'mode': '{}' is neither push nor pull", m));
    }
    push = m == "push";
  }
  Vector3 pivot_m;
  if (keys.has("pivot_mm") == keys.has("phi_deg")) {
    keys.fail(
        "give exactly one of 'pivot_mm' (X;Y;Z of the table pivot, mm, base frame) and 'phi_deg' (bar "
        "inclination to the circle's plane)");
  }
  if (keys.has("pivot_mm")) {
    const auto p = keys.numbers("pivot_mm", 3);
    pivot_m = Vector3(p[0], p[1], p[2]) * 1e-3;
  } else {
    if (!context.circle) {
      keys.fail("key 'phi_deg' places the pivot on a circle's axis and needs a circle path; give pivot_mm instead");
    }
    pivot_m = ldbb_pivot_for_circle(*context.circle, deg_to_rad(keys.number("phi_deg", 0.0)));
  }
  std::vector<std::unique_ptr<ForceModel>> models;
  for (double f : keys.numbers("force_N", 0)) {
    if (f <= 0.0) {
      keys.fail(fmt::format("key 'force_N': {} N is not a positive force (use mode=pull to reverse it)", f));
    }
    models.push_back(std::make_unique<LdbbForceModel>(pivot_m, f, push));
  }
  return models;
}

/// The six components of constant:/tool: specs; absent ones are 0, at least one is required.
Wrench parse_wrench_keys(const std::string& spec, const std::string& body) {
  static const char* const kKeys[6] = {"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"};
  const KeyValueSpec keys(spec, body, {kKeys[0], kKeys[1], kKeys[2], kKeys[3], kKeys[4], kKeys[5]});
  Wrench w = Wrench::Zero();
  bool any = false;
  for (int i = 0; i < 6; ++i) {
    any = any || keys.has(kKeys[i]);
    w[i] = keys.number(kKeys[i], 0.0);
  }
  if (!any) {
    keys.fail("give at least one of fx_N, fy_N, fz_N, mx_Nm, my_Nm, mz_Nm");
  }
  return w;
}

}  // namespace

Vector3 ldbb_pivot_for_circle(const CircleGeometry& circle, double phi_rad) {
  if (!std::isfinite(phi_rad) || std::abs(phi_rad) >= deg_to_rad(89.0)) {
    throw InputError(
        fmt::format("LDBB: inclination phi must be within +-89 deg (got {:.3f} deg)", rad_to_deg(phi_rad)));
  }
  if (!circle.normal.allFinite() || circle.normal.norm() < 1e-12) {
    throw InputError("LDBB: the circle's normal must be a finite, non-zero vector");
  }
  if (!circle.centre_m.allFinite()) {
    throw InputError("LDBB: the circle's centre is not finite");
  }
  if (!std::isfinite(circle.radius_m) || !(circle.radius_m > 0.0)) {
    throw InputError(fmt::format("LDBB: the circle's radius must be positive and finite (got {} m)", circle.radius_m));
  }
  return circle.centre_m - circle.normal.normalized() * (circle.radius_m * std::tan(phi_rad));
}

std::vector<std::unique_ptr<ForceModel>> parse_force_specs(const std::string& spec, const ForceSpecContext& context) {
  const auto colon = spec.find(':');
  const std::string kind = trim_blanks(spec.substr(0, colon));
  const std::string body = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "ldbb") {
    return parse_ldbb(spec, body, context);
  }
  if (kind == "constant" || kind == "tool") {
    std::vector<std::unique_ptr<ForceModel>> models;
    const Wrench w = parse_wrench_keys(spec, body);
    if (kind == "tool") {
      models.push_back(std::make_unique<ToolWrenchModel>(w));
    } else {
      models.push_back(std::make_unique<ConstantWrenchModel>(w));
    }
    return models;
  }
  if (kind == "table") {
    const std::string file = trim_blanks(body);
    if (file.empty()) {
      throw InputError(fmt::format("force spec '{}': give the CSV file after 'table:'", spec));
    }
    std::vector<std::unique_ptr<ForceModel>> models;
    models.push_back(std::make_unique<WrenchTableModel>(WrenchTableModel::read_file(file)));
    return models;
  }
  if (kind == "milling") {
    if (!context.milling) {
      throw InputError(
          fmt::format("force spec '{}': the milling force needs the cutter: give --cutter "
                      "\"diameter_mm=..,flutes=..,helix_deg=..\"",
                      spec));
    }
    return context.milling(spec);
  }
  throw InputError(fmt::format(
      "force spec '{}': unknown kind '{}' (use ldbb:..., constant:..., tool:..., table:FILE.csv or milling:...)", spec,
      kind));
}

std::unique_ptr<ForceModel> parse_force_spec(const std::string& spec, const ForceSpecContext& context) {
  auto models = parse_force_specs(spec, context);
  if (models.size() != 1) {
    throw InputError(fmt::format("force spec '{}': describes {} loads where one is expected", spec, models.size()));
  }
  return std::move(models.front());
}

}  // namespace deflex

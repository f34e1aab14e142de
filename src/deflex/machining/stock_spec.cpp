// Parser of the stock's specification.
#include "deflex/machining/stock_spec.hpp"

#include <fmt/format.h>

#include "deflex/machining/dexel_stock.hpp"
#include "deflex/machining/zmap_stock.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/key_value_spec.hpp"

namespace deflex {

std::unique_ptr<Stock> parse_stock_spec(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string kind = trim_blanks(spec.substr(0, colon));
  if (kind != "box") {
    throw InputError(fmt::format(
        "stock spec '{}': unknown kind '{}' (use box:min_mm=X;Y;Z,max_mm=X;Y;Z,cell_mm=C[,model=zmap|dexel])", spec,
        kind));
  }
  const std::string body = colon == std::string::npos ? "" : spec.substr(colon + 1);
  const KeyValueSpec keys(spec, body, {"min_mm", "max_mm", "cell_mm", "model", "layer_mm"});
  for (const char* required : {"min_mm", "max_mm", "cell_mm"}) {
    if (!keys.has(required)) keys.fail(fmt::format("key '{}' is required", required));
  }
  const auto lo = keys.numbers("min_mm", 3), hi = keys.numbers("max_mm", 3);
  const Vector3 min_m = Vector3(lo[0], lo[1], lo[2]) * 1e-3, max_m = Vector3(hi[0], hi[1], hi[2]) * 1e-3;
  for (int i = 0; i < 3; ++i) {
    if (!(max_m[i] > min_m[i])) {
      keys.fail(
          fmt::format("max_mm must exceed min_mm on every axis ({} is {:g} mm to {:g} mm)", "xyz"[i], lo[i], hi[i]));
    }
  }
  const double cell_mm = keys.number("cell_mm", 0.0);
  const std::string model = keys.has("model") ? keys.text("model") : "zmap";
  if (model != "zmap" && model != "dexel") keys.fail(fmt::format("key 'model': '{}' is neither zmap nor dexel", model));
  if (keys.has("layer_mm") && model != "dexel") keys.fail("key 'layer_mm' is the dexel model's layer spacing");
  for (const auto& [key, value] :
       {std::pair{"cell_mm", cell_mm}, std::pair{"layer_mm", keys.number("layer_mm", 1.0)}}) {
    if (!(value >= 0.001 && value <= 100.0))
      keys.fail(fmt::format("key '{}': {:g} mm is outside 0.001..100 mm", key, value));
  }
  try {
    if (model == "dexel") {
      return std::make_unique<DexelStock>(
          DexelStock::box(min_m, max_m, cell_mm * 1e-3, keys.number("layer_mm", cell_mm) * 1e-3));
    }
    return std::make_unique<ZMapStock>(ZMapStock::box(min_m, max_m, cell_mm * 1e-3));
  } catch (const InputError& e) {
    keys.fail(e.what());
  }
}

}  // namespace deflex

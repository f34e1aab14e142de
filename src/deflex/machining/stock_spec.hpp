// The stock of a machining run from the command line's text: a block, as a height map (the default,
// fast) or as dexels (walls to the micrometre, slower), in the workpiece frame.
//
//   box:min_mm=X;Y;Z,max_mm=X;Y;Z,cell_mm=C[,model=zmap|dexel][,layer_mm=L]
#pragma once

#include <memory>
#include <string>

#include "deflex/machining/stock.hpp"

namespace deflex {

/// The stock `spec` describes. `layer_mm` (dexel only; default the cell) is the dexels' layer
/// spacing. Throws InputError quoting the spec and naming the key: an unknown kind or key, a missing
/// key, a box whose max is not above its min on every axis, a cell or layer outside 0.001..100 mm, a
/// grid of too many nodes (the stock's own limits, naming the cell size to use).
[[nodiscard]] std::unique_ptr<Stock> parse_stock_spec(const std::string& spec);

}  // namespace deflex

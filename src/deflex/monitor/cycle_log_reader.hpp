// A recorded cycle log (`deflex online --log`) read back into the monitor's feed, for `deflex monitor
// --log` and the session's `--log-report`.
#pragma once

#include <memory>
#include <string>

#include "deflex/runtime/monitor_feed.hpp"

namespace deflex::monitor {

/// Reads the log (its joint_bound_deg and tcp_bound_mm columns give the bounds; an older log without
/// them is drawn without). Empty cells are values the cycle did not have. Throws DataError naming the
/// file and line: a missing column, a row with another number of cells than the header (a truncated
/// log), a cell that is not a number, time going back, no cycles.
std::shared_ptr<runtime::MonitorFeed> read_cycle_log_feed(const std::string& path);

}  // namespace deflex::monitor

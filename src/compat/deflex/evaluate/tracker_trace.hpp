// Deprecated: deflex/evaluate/tracker_trace.hpp moved to deflex/model/tracker_trace.hpp in deflex 0.2.0 (CHANGELOG.md);
// this forwarding header goes in 0.3.0. Include the new one (define DEFLEX_NO_DEPRECATED_HEADER_WARNINGS to silence the
// warning meanwhile).
#pragma once
#ifndef DEFLEX_NO_DEPRECATED_HEADER_WARNINGS
#pragma GCC warning \
    "deflex/evaluate/tracker_trace.hpp is deprecated: include deflex/model/tracker_trace.hpp (this header goes in deflex 0.3)"
#endif
#include "deflex/evaluate/tracker_csv.hpp"
#include "deflex/model/tracker_trace.hpp"

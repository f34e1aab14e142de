// Deprecated: deflex/online/payload_identification.hpp moved to deflex/identify/payload_identification.hpp in deflex
// 0.2.0 (CHANGELOG.md); this forwarding header goes in 0.3.0. Include the new one (define
// DEFLEX_NO_DEPRECATED_HEADER_WARNINGS to silence the warning meanwhile).
#pragma once
#ifndef DEFLEX_NO_DEPRECATED_HEADER_WARNINGS
#pragma GCC warning \
    "deflex/online/payload_identification.hpp is deprecated: include deflex/identify/payload_identification.hpp (this header goes in deflex 0.3)"
#endif
#include "deflex/identify/payload_identification.hpp"
